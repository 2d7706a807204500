"""The device settings (issue 34) on a machine without a GPU: torch's ``--device`` and Cycles'
``--render-device``, their spellings, what ``auto`` picks, and every fallback to the CPU with its line.
CUDA is faked by monkeypatching torch; nothing here needs a GPU (none was available to test on)."""
from __future__ import annotations

import argparse
import subprocess
import sys

import pytest
import torch

from isu_validate.devices import (TorchDevice, add_device_argument, add_render_device_argument,
                                  check_device_spec, check_render_device, resolve_torch_device)
from isu_validate.errors import InputError
from isu_validate.render import gpu


def _cuda(monkeypatch, count: int) -> None:
    monkeypatch.setattr(torch.cuda, "is_available", lambda: count > 0)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: count)
    monkeypatch.setattr(torch.cuda, "get_device_name", lambda device=None: "Fake GPU")


def _resolve(spec):
    lines: list[str] = []
    return resolve_torch_device(spec, warn=lines.append), lines


# ---- torch: --device auto|cpu|cuda[:N]|mps

@pytest.mark.parametrize("spec", ["gpu", "cuda:", "cuda:x", "cuda0", "tpu", "cpu:0"])
def test_a_malformed_device_is_a_user_error(spec):
    with pytest.raises(InputError, match="unknown device .*auto\\|cpu\\|cuda\\[:N\\]\\|mps"):
        check_device_spec(spec)


def test_spelling_is_forgiving_about_case_and_blanks():
    assert check_device_spec(" CUDA:1 ") == "cuda:1" and check_device_spec("") == "auto"


def test_auto_is_the_cpu_without_cuda(monkeypatch):
    _cuda(monkeypatch, 0)
    device, lines = _resolve("auto")
    assert device == TorchDevice("cpu", "auto") and lines == [] and device.describe() == "cpu"


def test_auto_takes_the_first_cuda_device_torch_sees(monkeypatch):
    _cuda(monkeypatch, 2)
    device, lines = _resolve("auto")
    assert device.name == "cuda:0" and not device.is_cpu and lines == []
    assert device.describe() == "cuda:0 (Fake GPU)"


def test_cuda_computes_float32_in_full_precision_and_the_cpu_leaves_torch_as_it_is(monkeypatch):
    import torch
    conv, matmul = torch.backends.cudnn.conv, torch.backends.cuda.matmul
    before = conv.fp32_precision, matmul.fp32_precision
    try:
        conv.fp32_precision, matmul.fp32_precision = "tf32", "tf32"
        _cuda(monkeypatch, 0)
        _resolve("cuda")                                                          # fell back: nothing changes
        assert conv.fp32_precision == "tf32"
        _cuda(monkeypatch, 1)
        assert _resolve("cuda")[0].name == "cuda:0"
        assert conv.fp32_precision == "ieee" and matmul.fp32_precision == "ieee"
    finally:
        conv.fp32_precision, matmul.fp32_precision = before


def test_cuda_absent_falls_back_with_one_line(monkeypatch):
    _cuda(monkeypatch, 0)
    device, lines = _resolve("cuda")
    assert device.is_cpu and device.asked == "cuda" and len(lines) == 1
    assert lines[0].startswith("device cuda is not available (torch sees no CUDA device")
    assert lines[0].endswith("torch work runs on the CPU")
    assert device.describe().startswith("cpu (asked cuda: torch sees no CUDA device")


def test_cuda_index_out_of_range_falls_back(monkeypatch):
    _cuda(monkeypatch, 1)
    device, lines = _resolve("cuda:1")
    assert device.is_cpu and lines == ["device cuda:1 is not available (cuda:1 asked, torch sees 1 CUDA "
                                       "device(s)); torch work runs on the CPU"]
    assert _resolve("cuda:0")[0].name == "cuda:0" and _resolve("cuda")[0].name == "cuda:0"


def test_mps_absent_falls_back(monkeypatch):
    monkeypatch.setattr(torch.backends.mps, "is_available", lambda: False)
    device, lines = _resolve("mps")
    assert device.is_cpu and lines == ["device mps is not available (this torch has no usable Apple MPS device); "
                                       "torch work runs on the CPU"]


def test_mps_present_is_taken(monkeypatch):
    monkeypatch.setattr(torch.backends.mps, "is_available", lambda: True)
    assert _resolve("mps")[0].name == "mps"


def test_the_default_warning_goes_to_stderr_once(monkeypatch, capsys):
    _cuda(monkeypatch, 0)
    resolve_torch_device("cuda:3")
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("warning: device cuda:3 is not available")


def test_a_resolved_device_passes_through():
    device = TorchDevice("cpu", "cuda", "gone")
    assert resolve_torch_device(device) is device


# ---- Cycles: --render-device auto|cpu|optix|cuda|hip|oneapi|metal

def test_the_flags_parse_and_refuse(capsys):
    parser = argparse.ArgumentParser()
    add_device_argument(parser)
    add_render_device_argument(parser)
    args = parser.parse_args(["--render-device", "OptiX", "--device", "cuda:1"])
    assert (args.render_device, args.device) == ("optix", "cuda:1")
    assert parser.parse_args([]).render_device == "auto"
    with pytest.raises(InputError, match="unknown render device 'vulkan'"):
        check_render_device("vulkan")


def test_render_auto_is_the_cpu_without_an_nvidia_gpu(monkeypatch):
    monkeypatch.setattr(gpu, "nvidia_compute_caps", lambda: [])
    assert gpu.resolve_render_device("auto") == "cpu"


def test_render_auto_takes_cuda_only_where_blender_ships_a_cubin(monkeypatch):
    monkeypatch.setattr(gpu, "shipped_cubins", lambda: {"86", "120"})
    monkeypatch.setattr(gpu, "nvidia_compute_caps", lambda: ["90"])   # an H100: PTX only, minutes to compile
    assert gpu.resolve_render_device("auto") == "cpu"
    monkeypatch.setattr(gpu, "nvidia_compute_caps", lambda: ["86"])
    assert gpu.resolve_render_device("auto") == "cuda"


def test_an_asked_render_device_is_left_to_the_worker():
    assert [gpu.resolve_render_device(d) for d in ("cpu", "optix", "metal")] == ["cpu", "optix", "metal"]


def test_the_shipped_cubins_are_read_from_bpy_without_importing_it():
    code = ("import sys; from isu_validate.render import gpu; s = gpu.shipped_cubins(); "
            "print(sorted(s, key=int), 'bpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    shipped, imported = out.rsplit(" ", 1)
    assert imported.strip() == "False"
    assert "'86'" in shipped and "'120'" in shipped and "'90'" not in shipped   # bpy 5.2.3, as issue 34 found


def test_no_nvidia_smi_means_no_gpu(monkeypatch):
    def absent(*a, **k):
        raise FileNotFoundError("nvidia-smi")
    monkeypatch.setattr(gpu.subprocess, "run", absent)
    assert gpu.nvidia_compute_caps() == []


def test_only_a_gpu_changes_the_render_cache_key():
    assert gpu.device_identity("cpu") == [] and gpu.device_identity("optix") == ["render-device:optix"]


# ---- every torch user takes the one setting (CPU only: CUDA absent or faked, nothing runs on it)

def test_inception_falls_back_names_the_device_and_keeps_the_cpus_cache(monkeypatch, tmp_path, capsys):
    from isu_validate.realism.features import FeatureExtractor
    _cuda(monkeypatch, 0)
    fallen = FeatureExtractor(cache=tmp_path, device="cuda:1")
    assert capsys.readouterr().err.startswith("warning: device cuda:1 is not available")
    assert fallen.report_settings()["device"].startswith("cpu (asked cuda:1: torch sees no CUDA device")
    cpu = FeatureExtractor(cache=tmp_path, device="cpu")
    assert fallen.cache.folder == cpu.cache.folder and cpu.report_settings()["device"] == "cpu"
    _cuda(monkeypatch, 1)   # a GPU's features are kept apart (how far they move was not measured)
    on_gpu = FeatureExtractor(cache=tmp_path, device="auto")
    assert on_gpu.device.name == "cuda:0" and on_gpu.cache.folder != cpu.cache.folder


def test_the_reference_sut_takes_the_device_through_open_sut(monkeypatch, capsys):
    from isu_validate.space import load_space
    from isu_validate.sut import open_sut
    _cuda(monkeypatch, 0)
    sut = open_sut("reference", space=load_space("isu-paper"), device="cuda")
    assert sut.adapter.device.startswith("cpu (asked cuda: ")
    assert sut.adapter.model.backbone.device.is_cpu
    assert capsys.readouterr().err.count("device cuda is not available") == 1


def test_devices_are_how_a_run_works_not_what_it_measures():
    from isu_validate.config import PipelineConfig, RunConfig
    plain = RunConfig(PipelineConfig(run_dir="a")).identity()
    assert RunConfig(PipelineConfig(run_dir="a", device="cuda", render_device="optix")).identity() == plain


def test_run_carries_both_flags_into_the_pipeline(tmp_path):
    from isu_validate.cli import build_parser
    from isu_validate.commands.run import config_from_args
    argv = ["run", "--out", str(tmp_path / "r"), "--device", "cuda:1", "--render-device", "optix"]
    config = config_from_args(build_parser(argv).parse_args(argv))
    assert (config.pipeline.device, config.pipeline.render_device) == ("cuda:1", "optix")


@pytest.mark.parametrize("command", [["run", "--out", "x"], ["render", "s.json", "--out", "x.png"],
                                     ["dataset", "--out", "x"], ["reference", "train"],
                                     ["bench", "render"]])
def test_every_rendering_command_has_the_render_device_flag(command):
    from isu_validate.cli import build_parser
    argv = [*command, "--render-device", "hip"]
    assert build_parser(argv).parse_args(argv).render_device == "hip"


@pytest.mark.parametrize("command", [["run", "--out", "x"], ["dataset", "--out", "x"], ["reference", "train"],
                                     ["realism", "a", "b"], ["stylize", "a.png", "--out", "x"],
                                     ["report", "r", "--out", "x"], ["agree", "p"],
                                     ["replay", "r", "--sut", "reference", "--out", "x"],
                                     ["sut", "check", "--sut", "reference", "i.png"],
                                     ["bench", "fid"], ["bench", "nst"]])
def test_every_torch_command_has_the_device_flag(command):
    from isu_validate.cli import build_parser
    argv = [*command, "--device", "cuda:2"]
    assert build_parser(argv).parse_args(argv).device == "cuda:2"


def test_a_gpu_without_a_shipped_kernel_gets_its_first_frame_time_to_compile(monkeypatch):
    monkeypatch.setattr(gpu, "shipped_cubins", lambda: {"86", "120"})
    monkeypatch.setattr(gpu, "nvidia_compute_caps", lambda: ["90"])   # an H100/H200: PTX only, ~7 min once
    note = gpu.first_frame_compiles("cuda")
    assert "sm_90" in note and f"{gpu.FIRST_FRAME_COMPILE_S:.0f} s" in note
    assert gpu.first_frame_compiles("optix") is not None            # OptiX's kernels are PTX only
    assert gpu.first_frame_compiles("cpu") is None and gpu.first_frame_compiles("hip") is None
    monkeypatch.setattr(gpu, "shipped_cubins", lambda: {"86", "90", "120"})   # compiled ahead, beside bpy's own
    assert gpu.first_frame_compiles("cuda") is None


def test_only_the_first_gpu_frame_waits_for_the_kernels(monkeypatch, capsys):
    from isu_validate.render import renderer as R

    monkeypatch.setattr(R, "first_frame_compiles", lambda device: "note: compiling" if device == "cuda" else None)
    r = R.BlenderRenderer.__new__(R.BlenderRenderer)   # the timeout logic alone: no worker, no Blender
    r.timeout_s, r.preset, r._kernels_ready = 240.0, R.get_preset("draft"), False
    r.preset = R.replace(r.preset, device="cuda")
    assert r._frame_timeout() == R.FIRST_FRAME_COMPILE_S and "compiling" in capsys.readouterr().err
    r._kernels_ready = True                                # set by a frame that came back
    assert r._frame_timeout() == 240.0
    r.preset, r._kernels_ready = R.replace(r.preset, device="optix"), False
    assert r._frame_timeout() == 240.0 and r._kernels_ready   # nothing to compile: the plain limit from now on
