"""``isu-validate exposure fit|apply|colour|check`` as a user types them (synthetic captures, no Blender)."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from capture.camera import load_camera, write_imaging, write_toml
from capture.camera_model import synthetic
from isu_validate.cli import main
from isu_validate.exr import write_exr
from isu_validate.srgb import srgb_encode_float


@pytest.fixture(scope="module")
def camera(tmp_path_factory):
    """A camera file carrying the synthetic camera's model (noise included)."""
    out = tmp_path_factory.mktemp("cam") / "cam.toml"
    return write_imaging(load_camera("default").source, synthetic.camera(), out)


def _exr(path: Path, linear: np.ndarray) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_exr(path, {c: linear[..., i] for i, c in enumerate("RGB")})
    return path


def test_apply_develops_an_exr_and_says_what_the_camera_chose(camera, tmp_path, capsys):
    exr = _exr(tmp_path / "x.exr", synthetic.scene(np.random.default_rng(0), (120, 160)) * 0.5)
    assert main(["exposure", "apply", str(exr), "--camera", str(camera), "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert Path(row["image"]).exists() and row["exposure"]["at_limit"] is None
    assert abs(row["exposure"]["metered"] - synthetic.camera().exposure.target) < 0.003


def test_apply_on_a_run_develops_every_render_and_resumes(camera, tmp_path, capsys):
    run = tmp_path / "run"
    rng = np.random.default_rng(1)
    for i, light in enumerate((0.0002, 0.3, 2.0)):
        _exr(run / "images" / f"t{i:04d}.exr", synthetic.scene(rng, (90, 120)) * light)
    assert main(["exposure", "apply", str(run), "--camera", str(camera)]) == 0
    out = run / "camera-default"
    assert sorted(p.name for p in out.glob("*.png")) == ["t0000.png", "t0001.png", "t0002.png"]
    rows = [json.loads(line) for line in (out / "exposure.jsonl").read_text().splitlines()]
    assert rows[0]["exposure"]["at_limit"] == "max" and rows[1]["exposure"]["at_limit"] is None
    before = (out / "t0001.png").stat().st_mtime_ns
    assert main(["exposure", "apply", str(run), "--camera", str(camera)]) == 0     # resumes: nothing redone
    assert (out / "t0001.png").stat().st_mtime_ns == before
    assert len((out / "exposure.jsonl").read_text().splitlines()) == 3
    other = write_imaging(camera, synthetic.camera(seed=1).with_part(noise=None), tmp_path / "c2.toml")
    assert main(["exposure", "apply", str(run), "--camera", str(other), "--out", str(out)]) == 2
    assert "another camera model" in capsys.readouterr().err


def test_apply_names_what_is_missing(tmp_path, capsys):
    (tmp_path / "run" / "images").mkdir(parents=True)
    plain = tmp_path / "plain.toml"        # the default rig without its auto-exposure table
    write_toml(replace(load_camera("default"), imaging=None), plain)
    assert main(["exposure", "apply", str(tmp_path / "run"), "--camera", str(plain)]) == 2
    assert "no imaging model" in capsys.readouterr().err
    camera = write_imaging(load_camera("default").source, synthetic.camera(), tmp_path / "c.toml")
    assert main(["exposure", "apply", str(tmp_path / "run"), "--camera", str(camera)]) == 2
    assert "--channels exr" in capsys.readouterr().err


def test_colour_writes_the_correction_and_extends_the_camera_file(camera, tmp_path, capsys):
    truth = synthetic.camera().with_part(noise=None)
    linear = synthetic.chart_scene(np.random.default_rng(5))
    real, _ = synthetic.apply(linear, truth)
    cv2.imwrite(str(tmp_path / "real.png"), cv2.cvtColor(real, cv2.COLOR_RGB2BGR))
    cv2.imwrite(str(tmp_path / "sim.png"), cv2.cvtColor((srgb_encode_float(linear) * 255 + 0.5).astype(np.uint8),
                                                        cv2.COLOR_RGB2BGR))
    args = ["exposure", "colour", "--real", str(tmp_path / "real.png"), "--sim", str(tmp_path / "sim.png"),
            "--out", str(tmp_path / "ccm.json"), "--camera", str(camera), "--camera-out", str(tmp_path / "cam3.toml")]
    assert main(args) == 0
    report = json.loads((tmp_path / "ccm.json").read_text())
    for key in ("de2000_before", "de2000_after"):
        assert set(report[key]) >= {"mean", "max"}
    assert report["method"] and report["de2000_after"]["mean"] < 2 < report["de2000_before"]["mean"]
    rig = load_camera(tmp_path / "cam3.toml")
    assert rig.imaging.colour.method == report["method"] and rig.imaging.colour.fit["de2000_after"]
    assert rig.imaging.response.white_balance == pytest.approx(report["white_balance"])
    assert "dE2000 mean" in capsys.readouterr().out


def test_colour_without_a_chart_names_the_file(tmp_path, capsys):
    cv2.imwrite(str(tmp_path / "nochart.png"), np.full((120, 160, 3), 90, np.uint8))
    assert main(["exposure", "colour", "--real", str(tmp_path / "nochart.png"), "--sim", "reference",
                 "--out", str(tmp_path / "c.json")]) == 2
    err = capsys.readouterr().err
    assert "nochart.png: no ColorChecker 24 found" in err and not (tmp_path / "c.json").exists()


def test_fit_on_a_single_exposure_says_what_to_capture(tmp_path, capsys):
    image, meta = synthetic.shoot(synthetic.camera(), synthetic.scene(np.random.default_rng(0), (60, 80)), 1,
                                  manual=(1000.0, 1.0))
    synthetic.write_frame(tmp_path / "one", "frame_0000", image, meta)
    assert main(["exposure", "fit", str(tmp_path / "one"), "--camera", "default",
                 "--out", str(tmp_path / "o.toml")]) == 2
    err = capsys.readouterr().err
    assert "exposure bracket" in err and not (tmp_path / "o.toml").exists()


def test_check_compares_pairs_and_escapes_names_in_html(tmp_path, capsys):
    rng = np.random.default_rng(3)
    for name in ("a", "b<script>"):
        linear = synthetic.scene(rng, (60, 80)) * 0.4
        for folder, gain in (("sim", 1.0), ("real", 1.6)):
            (tmp_path / folder).mkdir(exist_ok=True)
            cv2.imwrite(str(tmp_path / folder / f"{name}.png"),
                        (srgb_encode_float(linear * gain) * 255 + 0.5).astype(np.uint8))
    cv2.imwrite(str(tmp_path / "sim" / "lonely.png"), np.zeros((8, 8, 3), np.uint8))
    assert main(["exposure", "check", str(tmp_path / "sim"), str(tmp_path / "real"), "--out", str(tmp_path / "chk"),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["pairs"] == 2 and summary["mean_luma_difference"] > 0.05
    assert summary["unmatched"] == [str(tmp_path / "sim" / "lonely.png")]
    page = (tmp_path / "chk" / "report.html").read_text()
    assert "b&lt;script&gt;" in page and "<script>" not in page and page.count("data:image/png;base64") == 2


def test_check_reads_a_pairs_directory(tmp_path, capsys):
    rng = np.random.default_rng(4)
    for sample in ("s01", "s02"):
        linear = synthetic.scene(rng, (60, 80)) * 0.3
        (tmp_path / "pairs" / sample / "real").mkdir(parents=True)
        cv2.imwrite(str(tmp_path / "pairs" / sample / "sim.png"),
                    (srgb_encode_float(linear) * 255 + 0.5).astype(np.uint8))
        for k in range(2):
            cv2.imwrite(str(tmp_path / "pairs" / sample / "real" / f"frame_{k:04d}.png"),
                        (srgb_encode_float(linear * 0.7) * 255 + 0.5).astype(np.uint8))
    (tmp_path / "pairs" / "s03").mkdir()
    (tmp_path / "pairs" / "s03" / "scene.json").write_text("{}")     # recreated but not captured yet
    assert main(["exposure", "check", str(tmp_path / "pairs"), "--out", str(tmp_path / "chk"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["pairs"] == 4 and summary["mean_luma_difference"] < 0
    assert summary["unmatched"] == [str(tmp_path / "pairs" / "s03")]
