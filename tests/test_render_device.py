"""Cycles' render device with real Blender on a machine without a GPU (issue 34 part 3): every GPU type
is absent, so each must fall back to the CPU with one line, render CPU pixels and share the CPU's cache.
What a GPU renders was not tested (none was available); see docs/SETUP.md."""
from __future__ import annotations

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from isu_validate.render import Preset, open_renderer
from isu_validate.render.gpu import GPU_TYPES

pytestmark = pytest.mark.blender

TINY = Preset("tiny", 0.25, 1, False, "NONE", 1, 1, 1, 3.0, 1.5)   # 160x120, 1 sample: the pixels are not the point

_SELECT_EVERY_TYPE = """
import json, bpy
from isu_validate.render.blender.device import select_device
scene = bpy.context.scene
out = {}
for asked in ["cpu", *%r]:
    used, note = select_device(scene, asked)
    out[asked] = [used, note, scene.cycles.device, scene.cycles.denoising_use_gpu]
print("RESULT " + json.dumps(out))
"""


def test_every_gpu_type_falls_back_through_blenders_preferences():
    proc = subprocess.run([sys.executable, "-c", _SELECT_EVERY_TYPE % (list(GPU_TYPES),)], capture_output=True,
                          text=True, timeout=300)
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert proc.returncode == 0 and line, proc.stderr[-2000:]
    result = json.loads(line[0][len("RESULT "):])
    assert result["cpu"] == ["cpu", None, "CPU", False]
    for asked in GPU_TYPES:
        used, note, device, gpu_denoise = result[asked]
        assert (used, device, gpu_denoise) == ("cpu", "CPU", False), asked
        assert note.startswith(f"warning: render device {asked} is not available (") and \
            note.endswith("); Cycles renders on the CPU")
    assert "Blender lists no OPTIX device" in result["optix"][1]
    assert "no METAL backend" in result["metal"][1]   # Linux builds lack the enum value


def test_an_absent_gpu_renders_the_cpus_frame_under_the_cpus_cache_key(tmp_path, capfd):
    scene = {"driver_gender": "FEMALE", "driver_emotion": "SERIOUS", "driver_height": "H2", "driver_weight": "W2",
             "phone_position": "NONE", "seat_belt": "NO", "tshirt_colour": "WHITE", "child_seat": "NO",
             "car_lights": "OFF", "external_light": "MEDIUM", "luggage": "NO", "phone_codriver_seat": "NO",
             "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}
    cache, logs = tmp_path / "cache", tmp_path / "logs"
    with open_renderer(TINY, cache_dir=cache, log_dir=logs, device="cpu") as cpu:
        cpu_key = cpu.cache_key(cpu.space.check(scene))
        cpu.render(scene, tmp_path / "cpu.png")
    capfd.readouterr()
    with open_renderer(TINY, cache_dir=cache, log_dir=logs, device="optix") as optix:
        assert optix.cache_key(optix.space.check(scene)) != cpu_key      # a GPU's pixels keep apart
        first = optix.render(scene, tmp_path / "optix.png")
        second = optix.render(dict(scene, driver_gender="MALE"), tmp_path / "optix-2.png")
        err = capfd.readouterr().err
        assert optix.preset.device == "cpu" and optix.cache_key(optix.space.check(scene)) == cpu_key
    assert err.count("render device optix is not available") == 1, err
    assert "warning: render device optix is not available (Blender lists no OPTIX device); Cycles renders on " \
           "the CPU" in err
    assert first.cached and not second.cached     # the CPU's frame served the fallen-back renderer
    assert np.array_equal(cv2.imread(str(tmp_path / "cpu.png")), cv2.imread(str(first.image)))
    label = json.loads(first.channels["label"].read_text())
    assert label["render_device"] == "cpu" and label["cache_key"] == cpu_key
