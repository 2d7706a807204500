"""Fitting a camera from frames with sidecars: a synthetic camera with known parameters is the truth.
Hard cases: black and saturated frames, frames without sidecars, a single light level, a single exposure."""
from __future__ import annotations

import json
import shutil

import cv2
import numpy as np
import pytest

from capture.camera_model import frames, synthetic
from isu_validate.bench.exposure import response_error
from capture.camera_model.fit import fit_camera, plot_predictions
from capture.camera_model.model import ImagingModel
from capture.camera_model.response_fit import UnderdeterminedError

SIZE = (120, 160)
LIGHTS = (0.0003, 0.02, 0.1, 0.4, 1.0, 3.0)


@pytest.fixture(scope="module")
def truth():
    return synthetic.camera()


@pytest.fixture(scope="module")
def captures(truth, tmp_path_factory):
    out = tmp_path_factory.mktemp("captures")
    synthetic.capture_set(truth, out, seed=3, light_levels=LIGHTS, size=SIZE)
    return out


@pytest.fixture(scope="module")
def fitted(captures):
    return fit_camera([captures])


def test_the_fit_recovers_the_known_camera(fitted, truth):
    model = fitted.model
    assert model.exposure.target == pytest.approx(truth.exposure.target, rel=0.02)
    assert model.exposure.metering == "centre" and model.exposure.centre_sigma == 0.25
    assert model.exposure.order == "exposure_first"
    assert model.exposure.exposure_us[1] == pytest.approx(truth.exposure.exposure_us[1])
    assert model.exposure.gain[1] == pytest.approx(truth.exposure.gain[1])     # the darkest light reached the cap
    assert response_error(model.response, truth.response) < 0.03
    assert model.noise.shot == pytest.approx(truth.noise.shot, rel=0.35)
    assert model.noise.read == pytest.approx(truth.noise.read, rel=0.35)


def test_every_fitted_part_carries_its_data_and_residual(fitted):
    m = fitted.model
    assert m.response.fit["residual_codes"]["rms"] < 6 and len(m.response.fit["frames"]) >= 5
    assert len(m.exposure.fit["per_frame"]) == len(LIGHTS) * 2
    assert {"max", ""} <= {row["at_limit"] for row in m.exposure.fit["per_frame"]}
    assert m.exposure.fit["target_residual"]["relative_std"] < 0.02
    assert "centre 0.25" in m.exposure.fit["metering_candidates"]
    assert m.noise.fit["relative_rms_residual"] < 0.5 and m.noise.fit["samples"]
    assert m.exposure.fit["sensitivity_from"].startswith("assumed")
    assert any("sensitivity assumed" in w for w in fitted.warnings)


def test_measured_and_predicted_exposure_agree_and_are_plotted(fitted, tmp_path):
    inside = [p for p in fitted.predictions if p["measured_product"] < 16600 * 16 * 0.99]
    assert inside and all(abs(p["residual_log_product"]) < 0.05 for p in inside)
    assert plot_predictions(fitted, tmp_path / "p.png").stat().st_size > 5000


def test_black_and_saturated_frames_are_left_out_with_their_names(captures, tmp_path):
    folder = tmp_path / "set"
    shutil.copytree(captures, folder)
    sidecar = json.loads((folder / "auto" / "frame_0003.json").read_text())
    for name, value in (("black", 0), ("white", 255)):
        cv2.imwrite(str(folder / "auto" / f"{name}.png"), np.full((*SIZE, 3), value, np.uint8))
        (folder / "auto" / f"{name}.json").write_text(json.dumps(sidecar))
    result = fit_camera([folder])
    text = " ".join(result.warnings)
    assert "black.png" in text and "all black" in text and "white.png" in text and "saturated" in text
    assert np.isfinite(result.model.exposure.target) and np.all(np.isfinite(result.model.response.linear))


def test_frames_without_sidecars_are_named_and_none_at_all_is_a_clear_error(captures, tmp_path):
    folder = tmp_path / "nosidecars"
    shutil.copytree(captures / "auto", folder)
    (folder / "frame_0001.json").unlink()
    data = frames.load([folder])
    assert any("frame_0001.png" in w and "no sidecar" in w for w in data.warnings())
    for sidecar in folder.glob("*.json"):
        sidecar.unlink()
    with pytest.raises(UnderdeterminedError, match="no usable frame.*no sidecar"):
        fit_camera([folder])


def test_a_single_light_level_asks_for_more_light_levels(truth, tmp_path):
    rng = np.random.default_rng(0)
    still = synthetic.scene(rng, SIZE)
    for i in range(4):   # the same scene, light and exposure: one light level
        image, meta = synthetic.shoot(truth, still, i)
        synthetic.write_frame(tmp_path / "auto", f"frame_{i:04d}", image, meta)
    with pytest.raises(UnderdeterminedError, match="single light level.*two clearly different light levels"):
        fit_camera([tmp_path / "auto"], ImagingModel(response=truth.response))


def test_a_single_exposure_asks_for_a_bracket(truth, captures, tmp_path):
    one = tmp_path / "one"
    one.mkdir()
    for f in sorted((captures / "bracket").glob("frame_03_*")):
        shutil.copy(f, one / f.name)
    with pytest.raises(UnderdeterminedError, match="1 exposure setting.*exposure bracket"):
        fit_camera([one])


def test_corrupt_and_unreadable_frames_are_set_aside(captures, tmp_path):
    folder = tmp_path / "bad"
    shutil.copytree(captures / "bracket", folder)
    (folder / "frame_00_0.png").write_bytes(b"not a png")
    (folder / "frame_00_1.json").write_text("{broken")
    data = frames.load([folder])
    reasons = dict(data.excluded)
    assert "cannot be read" in reasons[str(folder / "frame_00_0.png")]
    assert "not valid JSON" in reasons[str(folder / "frame_00_1.png")]


def test_renders_of_the_captured_scenes_fit_the_sensitivity(truth, tmp_path):
    """Auto-exposed frames with linear renders of the same scenes (``--sim``) tie render light to the camera."""
    from isu_validate.exr import write_exr
    rng = np.random.default_rng(8)
    for i, light in enumerate((0.02, 0.1, 0.5, 2.0)):
        linear = synthetic.scene(rng, SIZE) * light
        image, meta = synthetic.shoot(truth, linear, i)
        synthetic.write_frame(tmp_path / "auto", f"frame_{i:04d}", image, meta)
        (tmp_path / "sim").mkdir(exist_ok=True)
        write_exr(tmp_path / "sim" / f"frame_{i:04d}.exr", {c: linear[..., k] for k, c in enumerate("RGB")})
    result = fit_camera([tmp_path / "auto"], ImagingModel(response=truth.response), sim_dir=tmp_path / "sim")
    ae = result.model.exposure
    assert ae.sensitivity == pytest.approx(truth.exposure.sensitivity, rel=0.1)
    assert ae.fit["sensitivity_from"].startswith("renders: 4 pairs")
    assert not any("sensitivity assumed" in w for w in result.warnings)
