"""The imaging model in the camera file, and applying it to linear light (synthetic frames, no Blender)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from capture.camera import CameraFileError, camera_from_dict, load_camera, read_toml, write_imaging, write_toml
from capture.camera_model import synthetic
from capture.camera_model.apply import apply
from capture.camera_model.model import AutoExposure, ImagingModel, ImagingModelError, Noise, Response, from_dict
from isu_validate.render import BlenderRenderer
from isu_validate.srgb import srgb_encode


def _scene(light=1.0, size=(120, 160)):
    return synthetic.scene(np.random.default_rng(1), size) * light


def test_a_camera_file_without_imaging_tables_has_no_model_and_keeps_its_cache_key(tmp_path):
    plain = tmp_path / "plain.toml"      # the default rig without its auto-exposure table
    write_toml(replace(load_camera("default"), imaging=None), plain)
    rig = load_camera(plain)
    assert rig.imaging is None
    assert read_toml(rig.source).imaging is None
    assert load_camera("default").imaging.exposure is not None     # the shipped rig auto-exposes
    plain = BlenderRenderer("draft", rig)
    with_model = BlenderRenderer("draft", _rig_with(synthetic.camera()))
    assert plain.imaging is None and with_model.imaging is not None
    assert plain.cache_key({}) != with_model.cache_key({})   # the model changes what the camera records


def _rig_with(model: ImagingModel):
    return replace(load_camera("default"), imaging=model)


def test_the_model_round_trips_through_the_camera_file(tmp_path):
    model = synthetic.camera()
    out = write_imaging(load_camera("default").source, model, tmp_path / "cam.toml")
    rig = load_camera(out)
    assert rig.imaging.hash == model.hash
    assert rig.imaging.exposure == model.exposure
    np.testing.assert_allclose(rig.imaging.response.linear, model.response.linear)
    np.testing.assert_allclose(rig.imaging.colour.matrix, model.colour.matrix)
    assert read_toml(out).imaging.hash == model.hash
    # intrinsics and pose are kept as they were
    assert (rig.fx, rig.position, rig.rotation) == (load_camera("default").fx, load_camera("default").position,
                                                    load_camera("default").rotation)


@pytest.mark.parametrize("table, message", [
    ({"exposure": {"target": 1.5}}, "target"),
    ({"exposure": {"exposure_us": [100, 10]}}, "min above max"),
    ({"exposure": {"order": "sideways"}}, "order"),
    ({"exposure": {"roi": [0.5, 0.5, 0.2, 0.9]}}, "roi"),
    ({"response": {"linear_r": [0.0] * 10, "linear_g": [0.0] * 10, "linear_b": [0.0] * 10}}, "256"),
    ({"response": {"linear_r": list(np.linspace(1, 0, 256)), "linear_g": list(np.linspace(0, 1, 256)),
                   "linear_b": list(np.linspace(0, 1, 256))}}, "monotonic"),
    ({"colour": {"matrix": [[1, 0], [0, 1]]}}, "3 rows"),
    ({"noise": {"shot": -1}}, "shot"),
])
def test_a_broken_imaging_table_names_the_file_and_the_key(table, message):
    raw = {"image": {"width": 64, "height": 48}, "intrinsics": {"fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5},
           "extrinsics": {"position": [0, 0, 1], "look_at": [-1, 0, 1]}, **table}
    with pytest.raises(ImagingModelError, match=message) as err:
        from_dict(raw, "cam.toml")
    assert "cam.toml" in str(err.value)
    with pytest.raises(CameraFileError, match=message):
        camera_from_dict(raw, "cam.toml")


def test_auto_exposure_meets_its_target_at_any_light_within_the_limits():
    model = synthetic.camera().with_part(noise=None)
    for light in (0.05, 0.3, 1.0, 3.0):
        image, exposure = apply(_scene(light), model)
        assert exposure.at_limit is None
        assert abs(exposure.metered - model.exposure.target) < 0.002
        t0, t1 = model.exposure.exposure_us
        assert t0 <= exposure.exposure_us <= t1


def test_dark_and_bright_scenes_hit_the_limits_and_show_it():
    model = synthetic.camera().with_part(noise=None)
    dark_image, dark = apply(_scene(0.0005), model)
    assert dark.at_limit == "max" and dark.metered < model.exposure.target
    assert (dark.exposure_us, dark.gain) == (model.exposure.exposure_us[1], model.exposure.gain[1])
    bright_image, bright = apply(_scene(500.0), model)
    assert bright.at_limit == "min" and bright.metered > model.exposure.target
    assert dark_image.mean() < 0.3 * bright_image.mean()


def test_exposure_time_is_spent_before_gain_or_after_it_as_the_camera_does():
    ae = AutoExposure(exposure_us=(100.0, 10000.0), gain=(1.0, 8.0), order="exposure_first")
    assert ae.split(5000.0) == (5000.0, 1.0)
    assert ae.split(40000.0) == (10000.0, 4.0)
    gain_first = AutoExposure(exposure_us=(100.0, 10000.0), gain=(1.0, 8.0), order="gain_first")
    assert gain_first.split(400.0) == (100.0, 4.0)
    assert gain_first.split(4000.0) == (500.0, 8.0)


def test_a_camera_still_converging_is_off_target_and_a_converged_one_is_not():
    converging = synthetic.camera().with_part(noise=None)
    slow = converging.with_part(exposure=replace(converging.exposure, frames=2, speed=0.3, start_exposure=100.0))
    _, first = apply(_scene(1.0), slow)
    _, settled = apply(_scene(1.0), converging)
    assert abs(first.metered - slow.exposure.target) > 0.05
    assert abs(settled.metered - converging.exposure.target) < 0.002


def test_noise_grows_with_gain_and_is_seeded():
    model = synthetic.camera()
    flat = np.full((120, 160, 3), 0.05, np.float32)
    low, _ = apply(flat, model, seed=1, manual=(4000.0, 1.0))
    high, _ = apply(flat / 8, model, seed=1, manual=(4000.0, 8.0))     # the same signal, 8x the gain
    assert abs(high[..., 1].mean() - low[..., 1].mean()) < 2
    assert high[..., 1].std() > 2 * low[..., 1].std()
    again, _ = apply(flat, model, seed=1, manual=(4000.0, 1.0))
    other, _ = apply(flat, model, seed=2, manual=(4000.0, 1.0))
    assert np.array_equal(low, again) and not np.array_equal(low, other)


def test_a_model_with_only_an_srgb_response_develops_like_the_plain_renderer():
    linear = _scene(0.8)
    image, exposure = apply(linear, ImagingModel(response=Response.srgb()))
    assert exposure is None
    assert np.abs(image.astype(int) - srgb_encode(linear).astype(int)).max() <= 1


@pytest.mark.parametrize("kind", ["black", "saturated"])
def test_black_and_saturated_renders_develop_to_finite_frames(kind):
    model = synthetic.camera()
    linear = np.zeros((48, 64, 3), np.float32) if kind == "black" else np.full((48, 64, 3), 1e6, np.float32)
    image, exposure = apply(linear, model)
    assert image.dtype == np.uint8 and np.isfinite(exposure.metered)
    assert exposure.at_limit == ("max" if kind == "black" else "min")
    assert image.mean() < 60 if kind == "black" else image.min() == 255   # black: noise at full gain


def test_noise_variance_follows_shot_plus_read():
    n = Noise(shot=1e-3, read=1e-2)
    assert n.variance(0.5, 2.0) == pytest.approx(1e-3 * 2 * 0.5 + (1e-2 * 2) ** 2)


def test_the_camera_meters_a_frame_it_recorded_at_the_level_it_chose():
    """One metering pipeline: the level ``apply`` steered a render to is the level ``meter_frame`` reads
    back from the recorded frame, and ``exposure fit``'s prediction from the recovered scene is the
    exposure ``apply`` chose (no noise, no colour correction: nothing else may differ)."""
    from capture.camera_model.apply import auto_expose, forward_curve
    from capture.camera_model.metering import meter_frame
    model = synthetic.camera().with_part(noise=None, colour=None)
    ae = model.exposure
    image, chosen = apply(_scene(0.3), model)
    assert chosen.at_limit is None
    read_back = meter_frame(image / 255.0, model.curve, ae.metering, ae.centre_sigma, ae.roi)
    assert read_back == pytest.approx(chosen.metered, abs=2e-3)      # 8-bit rounding only
    scene = model.curve.to_linear(image / 255.0) / (chosen.exposure_us * 1e-6 * chosen.gain * ae.sensitivity)
    predicted = auto_expose(scene, ae, forward_curve(model.curve))
    assert predicted.exposure_us * predicted.gain == pytest.approx(chosen.exposure_us * chosen.gain, rel=0.02)
