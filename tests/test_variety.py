"""Variety for training data (``render/variety.py``): the camera jittered per scene through ``Camera.nudged``
and sensor effects after rendering. Seeded draws repeat, zero strengths change nothing, each effect moves
pixels by what it says, a dataset records and refuses to resume with other variety, and (with real Blender,
one tiny render) the labels are the jittered camera's."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from capture.camera import load_camera
from isu_validate.cli import main
from isu_validate.errors import InputError
from isu_validate.protocols import RenderResult
from isu_validate.render import Preset
from isu_validate.render.camera_jitter import CameraJitter, parse_camera_jitter
from isu_validate.render.sensor_effects import RECIPES, SensorEffects, apply_drawn, parse_sensor_effects
from isu_validate.render.variety import Variety, VariedRenderer, vary
from isu_validate.space import load_space
from isu_validate.srgb import srgb_to_linear

SPACE = load_space()
SCENES = [SPACE.canonical(s) for s in SPACE.sample(np.random.default_rng(0), 3)]
RIG = load_camera("default")
DOUBLE = "tests.dataset_doubles:renderer"


class _CameraHolder:
    """Stands in for a renderer where only the camera matters: it records the cameras it is asked to use."""

    def __init__(self):
        self.space, self.rig, self.used = SPACE, RIG, []

    def use_camera(self, camera):
        self.used.append(camera)

    def cache_key(self, canonical):
        return f"{self.used[-1].hash if self.used else RIG.hash}:{SPACE.key(canonical)}"

    def close(self):
        pass


def _photo() -> np.ndarray:
    """A mid-grey image with smooth shading and sharp 8 px checks (no clipping under the effects' strengths)."""
    rng = np.random.default_rng(7)
    base = cv2.GaussianBlur(rng.uniform(70, 180, (120, 160, 3)), (0, 0), 3)
    y, x = np.mgrid[0:120, 0:160]
    checks = np.where((y // 8 + x // 8) % 2, 25.0, -25.0)[..., None]
    return np.clip(base + checks, 0, 255).astype(np.uint8)


def _effect(**strength) -> dict:
    """Drawn strengths with everything off but ``strength``."""
    off = {"exposure_stops": 0.0, "white_balance": [0.0, 0.0], "vignette": 0.0, "blur_sigma": 0.0,
           "noise_sigma": 0.0, "jpeg_quality": None, "noise_seed": 5}
    return {**off, **strength}


# ---------------------------------------------------------------- the camera moved through Camera.nudged
def test_a_nudged_camera_moves_turns_and_zooms_as_it_says():
    ahead = RIG.t + 2.0 * RIG.R[:, 2]                       # a point 2 m down the optical axis
    centre = RIG.project(ahead)[0]
    assert np.allclose(centre, [RIG.cx, RIG.cy], atol=1e-6)
    panned = RIG.nudged(turn_deg=(0.0, 4.0, 0.0)).project(ahead)[0]
    assert abs(abs(panned[0] - RIG.cx) - RIG.fx * np.tan(np.radians(4.0))) < 1e-6 and abs(panned[1] - RIG.cy) < 1e-6
    shift = np.array([0.03, -0.02, 0.01])
    point = RIG.t + np.array([-1.0, 0.2, -0.4])
    assert np.allclose(RIG.nudged(shift=shift).project(point), RIG.project(point - shift), atol=1e-9)
    zoomed = RIG.nudged(focal_scale=1.1)
    assert np.allclose(zoomed.project(point) - [RIG.cx, RIG.cy], 1.1 * (RIG.project(point) - [RIG.cx, RIG.cy]))
    assert (zoomed.position, zoomed.rotation, zoomed.imaging, zoomed.source) == (RIG.position, RIG.rotation,
                                                                                  RIG.imaging, RIG.source)
    assert RIG.nudged().hash == RIG.hash and zoomed.hash != RIG.hash


def test_the_jitter_is_seeded_per_scene_and_bounded():
    variety = Variety.parse("pos=0.05,angle=5,focal=0.1", None, seed=3)
    first = VariedRenderer(_CameraHolder(), variety)
    again = VariedRenderer(_CameraHolder(), variety)
    other_seed = VariedRenderer(_CameraHolder(), replace(variety, seed=4))
    draws = [first.camera_for(s) for s in SCENES]
    for scene, (camera, drawn) in zip(SCENES, draws):
        assert again.camera_for(scene)[1] == drawn and again.camera_for(scene)[0].hash == camera.hash
        assert other_seed.camera_for(scene)[1] != drawn
        assert max(map(abs, drawn["shift_m"])) <= 0.05 and max(map(abs, drawn["turn_deg"])) <= 5
        assert 0.9 <= drawn["focal_scale"] <= 1.1
        assert camera.geometry() == RIG.nudged(drawn["shift_m"], drawn["turn_deg"], drawn["focal_scale"]).geometry()
    assert len({d[0].hash for d in draws}) == len(SCENES)           # each scene its own camera
    keys = [first.cache_key(s) for s in SCENES]
    assert keys == [again.cache_key(s) for s in SCENES] and keys != [other_seed.cache_key(s) for s in SCENES]


def test_a_scenes_key_follows_its_draw_not_the_wording_and_the_camera_is_drawn_once(monkeypatch):
    variety = Variety.parse("pos=0.05,angle=5,focal=0.1", "mild", seed=3)
    renderer = VariedRenderer(_CameraHolder(), variety)
    keys = [renderer.cache_key(s) for s in SCENES]
    assert len(set(keys)) == len(SCENES)
    effects_off = VariedRenderer(_CameraHolder(), replace(variety, effects=SensorEffects()))
    assert [effects_off.cache_key(s) for s in SCENES] != keys       # the effects decide the image too
    monkeypatch.setattr(Variety, "describe", lambda self: {**self.spec(), "per_scene": "reworded"})
    assert [VariedRenderer(_CameraHolder(), variety).cache_key(s) for s in SCENES] == keys
    draws = []
    original = CameraJitter.draw
    monkeypatch.setattr(CameraJitter, "draw", lambda self, rig, rng: draws.append(1) or original(self, rig, rng))
    fresh = VariedRenderer(_CameraHolder(), variety)
    fresh.cache_key(SCENES[0])
    camera, _ = fresh.camera_for(SCENES[0])
    assert len(draws) == 1 and fresh.inner.used[-1].hash == camera.hash
    fresh.camera_for(SCENES[1])
    assert len(draws) == 2


def test_off_means_the_renderer_itself_and_zero_means_identity():
    holder = _CameraHolder()
    assert vary(holder, Variety()) is holder and vary(holder, Variety.parse("", "none", 1)) is holder
    assert parse_camera_jitter("pos=0,angle=0,focal=0") == CameraJitter() and not CameraJitter().active
    image = _photo()
    for spec in ("noise=0,blur=0,jpeg=0,vignette=0,exposure=0,white_balance=0", "none"):
        effects = parse_sensor_effects(spec)
        assert not effects.active
        out, _ = effects.apply(image, np.random.default_rng(1))
        assert out.tobytes() == image.tobytes(), spec
    assert apply_drawn(image, _effect()).tobytes() == image.tobytes()


# ---------------------------------------------------------------- sensor effects
def test_each_effect_changes_pixels_by_what_it_says():
    image = _photo()
    levels = image.astype(float)
    noisy = apply_drawn(image, _effect(noise_sigma=0.02)).astype(float)
    assert abs((noisy - levels).std() - 0.02 * 255) < 0.1 * 0.02 * 255 and abs((noisy - levels).mean()) < 0.2
    blurred = apply_drawn(image, _effect(blur_sigma=1.5)).astype(float)
    assert np.abs(blurred - levels).mean() > 0.5 and abs(blurred.mean() - levels.mean()) < 0.5
    assert np.abs(np.diff(blurred, axis=1)).mean() < np.abs(np.diff(levels, axis=1)).mean()   # fewer edges
    brighter = apply_drawn(image, _effect(exposure_stops=0.5))
    ratio = srgb_to_linear(brighter / 255.0).mean() / srgb_to_linear(image / 255.0).mean()
    assert abs(ratio - 2 ** 0.5) < 0.02
    warm = apply_drawn(image, _effect(white_balance=[0.1, -0.1]))
    linear, before = srgb_to_linear(warm / 255.0), srgb_to_linear(image / 255.0)
    assert np.array_equal(warm[..., 1], image[..., 1])                                  # green kept
    assert abs(linear[..., 2].mean() / before[..., 2].mean() - 1.1) < 0.02              # red (BGR) up 10 %
    assert abs(linear[..., 0].mean() / before[..., 0].mean() - 0.9) < 0.02              # blue down 10 %
    dim = apply_drawn(image, _effect(vignette=0.4))
    h, w = image.shape[:2]
    assert np.abs(dim[h // 2 - 2:h // 2 + 2, w // 2 - 2:w // 2 + 2].astype(int) - image[h // 2 - 2:h // 2 + 2,
                  w // 2 - 2:w // 2 + 2]).max() <= 1
    corner = srgb_to_linear(dim[0, 0] / 255.0) / srgb_to_linear(image[0, 0] / 255.0)
    assert np.allclose(corner, 0.6, atol=0.03)
    jpeg = apply_drawn(image, _effect(jpeg_quality=30)).astype(float)
    psnr = 10 * np.log10(255 ** 2 / ((jpeg - levels) ** 2).mean())
    assert 25 < psnr < 60


def test_effects_are_seeded_bounded_and_recorded():
    effects = parse_sensor_effects("strong")
    assert effects == SensorEffects(**RECIPES["strong"])
    assert parse_sensor_effects("mild,jpeg=0.9").jpeg == 0.9 and parse_sensor_effects("mild,jpeg=0.9").noise == 0.012
    image = _photo()
    a, drawn = effects.apply(image, np.random.default_rng(11))
    b, again = effects.apply(image, np.random.default_rng(11))
    c, other = effects.apply(image, np.random.default_rng(12))
    assert a.tobytes() == b.tobytes() and drawn == again and c.tobytes() != a.tobytes() and other != drawn
    assert apply_drawn(image, drawn).tobytes() == a.tobytes()                  # the record rebuilds the image
    for seed in range(30):
        d = effects.draw(np.random.default_rng(seed))
        assert abs(d["exposure_stops"]) <= 0.7 and max(map(abs, d["white_balance"])) <= 0.12
        assert 0 <= d["vignette"] <= 0.45 and 0 <= d["blur_sigma"] <= 1.6 and 0 <= d["noise_sigma"] <= 0.03
        assert 36 <= d["jpeg_quality"] <= 100


@pytest.mark.parametrize("jitter, effects, says", [
    ("pos=0.5", None, "pos must be between 0 and 0.1"),
    ("angle=five", None, "angle='five' is not a number"),
    ("tilt=3", None, "is not KEY=VALUE with KEY one of pos, angle, focal"),
    (None, "grainy", "unknown recipe 'grainy'"),
    (None, "noise=2", "noise must be between 0 and 0.1"),
    (None, "sharpen=1", "unknown effect 'sharpen'"),
])
def test_bad_specs_say_what_is_wrong(jitter, effects, says):
    with pytest.raises(InputError, match=says):
        Variety.parse(jitter, effects, 0)


# ---------------------------------------------------------------- a dataset with variety (the test double)
def _dataset(out: Path, *extra: str) -> int:
    return main(["dataset", "--out", str(out), "--renderer-factory", DOUBLE, *extra])


def _rows(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "metadata.jsonl").read_text().splitlines()]


def test_a_dataset_records_its_sensor_effects_repeats_them_and_refuses_other_variety_on_resume(tmp_path, capsys):
    assert _dataset(tmp_path / "a", "--n", "3", "--seed", "2", "--sensor-effects", "strong") == 0
    assert _dataset(tmp_path / "b", "--n", "3", "--seed", "2", "--sensor-effects", "strong") == 0
    assert _dataset(tmp_path / "plain", "--n", "3", "--seed", "2") == 0
    rows, again, plain = _rows(tmp_path / "a"), _rows(tmp_path / "b"), _rows(tmp_path / "plain")
    assert len(rows) == len(again) == len(plain) == 3
    for row, twin, untouched in zip(rows, again, plain, strict=True):
        assert row["variety"] == twin["variety"] and set(row["variety"]) == {"sensor"}
        image = (tmp_path / "a" / row["file_name"]).read_bytes()
        assert image == (tmp_path / "b" / row["file_name"]).read_bytes()
        assert image != (tmp_path / "plain" / untouched["file_name"]).read_bytes() and "variety" not in untouched
    info = json.loads((tmp_path / "a" / "dataset.json").read_text())
    assert info["seeds"] == {"scenes": 2, "style_noise": 2, "sensor_effects": 2}
    assert info["variety"]["sensor_effects"] == parse_sensor_effects("strong").text and info["variety"]["seed"] == 2
    assert "sensor_effects" not in json.loads((tmp_path / "plain" / "dataset.json").read_text())["identity"]
    card = (tmp_path / "a" / "DATASET_CARD.md").read_text()
    assert "sensor effects: `exposure=0.7," in card and "--sensor-effects exposure=0.7," in info["reproduce"]
    capsys.readouterr()
    for flags, says in ((["--sensor-effects", "mild"], "sensor_effects: 'exposure=0.7"),
                        (["--camera-jitter", "angle=2"], "camera_jitter: None (stored) vs 'pos=0,angle=2,focal=0'")):
        assert _dataset(tmp_path / "a", "--resume", *flags) == 2
        err = capsys.readouterr().err
        assert "was started with other settings" in err and says in err, err
    assert _dataset(tmp_path / "plain", "--resume", "--sensor-effects", "mild") == 2
    assert "sensor_effects: None (stored)" in capsys.readouterr().err
    assert _dataset(tmp_path / "a", "--resume", "--sensor-effects", "strong") == 0   # the same spec: resumes


def test_a_camera_jitter_needs_a_renderer_that_moves_its_camera(tmp_path, capsys):
    assert _dataset(tmp_path / "ds", "--n", "2", "--camera-jitter", "angle=3") == 2
    err = capsys.readouterr().err
    assert "--camera-jitter needs a renderer that can move its camera" in err and len(err.strip().splitlines()) == 1
    assert _dataset(tmp_path / "ds2", "--n", "2", "--camera-jitter", "pos=1") == 2
    assert "pos must be between 0 and 0.1" in capsys.readouterr().err and not (tmp_path / "ds2").exists()
    assert _dataset(tmp_path / "ds3", "--n", "2", "--camera-mix", "passenger-door") == 2
    assert "--camera-mix needs a renderer that can move its camera" in capsys.readouterr().err


# ---------------------------------------------------------------- the labels follow the camera (real Blender)
TINY = Preset("test", 0.3125, 2, False, "NONE", 2, 1, 1, 3.0, 1.5)


@pytest.mark.blender
def test_the_labels_of_a_jittered_render_are_the_jittered_cameras(tmp_path):
    from isu_validate.render import open_renderer
    from isu_validate.render.labels import INSTANCE_ID
    from isu_validate.render.object_axes import seat_objects_up

    scene = {**SCENES[0], "child_seat": "NO", "colacan_codriver_seat": "YES", "colabottle_codriver_seat": "YES"}
    scene = SPACE.canonical({k: v for k, v in scene.items() if k not in ("child", "child_seat_orientation")})
    renderer = vary(open_renderer(TINY, camera=replace(RIG, imaging=None), channels=("seg",),
                                  log_dir=tmp_path / "logs"), Variety.parse("pos=0.04,angle=8,focal=0.1", "mild", 5))
    try:
        camera, drawn = renderer.camera_for(scene)
        result = renderer.render(scene, tmp_path / "frame.png")
        render_rig = renderer.inner.render_rig
    finally:
        renderer.close()
    assert render_rig.geometry() == camera.scaled(TINY.scale).geometry()
    label = json.loads(result.channels["label"].read_text())
    assert label["camera"] == render_rig.geometry() and label["variety"]["camera"] == drawn
    assert set(label["variety"]["sensor"]) >= {"noise_sigma", "jpeg_quality"} and result.variety == {
        "camera": drawn, "sensor": label["variety"]["sensor"]}
    assert result.up == {k: v for k, v in seat_objects_up(renderer.inner.cabin, render_rig).items() if k in result.up}
    assert "colabottle_codriver_seat" in result.up
    # the can's middle, projected through the jittered camera, lies on the can's pixels; through the rig, off them
    seg = cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED)
    ys, xs = np.nonzero(seg == INSTANCE_ID["colacan_codriver_seat"])
    middle = np.array(renderer.inner.cabin["codriver_seat"]["colacan_codriver_seat"]["position"]) + [0, 0, 0.06]
    seen = render_rig.project(middle)[0]
    plain = RIG.scaled(TINY.scale).project(middle)[0]
    assert np.linalg.norm(seen - plain) > 4, "the draw moved the camera too little to tell"
    assert xs.min() - 1 <= seen[0] <= xs.max() + 1 and ys.min() - 1 <= seen[1] <= ys.max() + 1
    assert not (xs.min() - 1 <= plain[0] <= xs.max() + 1 and ys.min() - 1 <= plain[1] <= ys.max() + 1)


# ---------------------------------------------------------------- the reference ISU's card
class _Painter:
    """Stands in for the renderer of `reference train`: the T-shirt's colour as a big patch."""

    def __init__(self):
        self.space = SPACE

    def render(self, scene, out: Path):
        image = np.full((120, 160, 3), 90, np.uint8)
        image[60:110, 10:60] = 255 if scene["tshirt_colour"] == "WHITE" else 0
        cv2.imwrite(str(out), image)
        return RenderResult(Path(out))

    def close(self):
        pass


def test_the_model_card_records_the_variety_its_sets_were_rendered_with(tmp_path):
    from isu_validate.reference.backbone import Backbone
    from isu_validate.reference.feature_bank import load_bank
    from isu_validate.reference.training import train_reference

    variety = Variety.parse(None, "strong", 3)
    renderer = vary(_Painter(), variety)
    card = train_reference(SPACE, renderer, tmp_path / "model", tmp_path / "work", n_train=24, n_test=8, seed=3,
                           preset="painted", backbone=Backbone(160, 120, threads=2), variety=variety.describe())
    assert card["variety"] == variety.describe() and card["variety"]["seed"] == 3
    markdown = (tmp_path / "model" / "MODEL_CARD.md").read_text()
    assert f"  - sensor effects: `{variety.effects.text}` (each image" in markdown
    assert "  - seed 3; per scene" in markdown
    assert f"--sensor-effects {variety.effects.text}`" in markdown
    train, _ = load_bank(tmp_path / "model", SPACE, "")
    assert train.meta["variety"] == variety.describe()
    painted = cv2.imread(str(tmp_path / "work" / "train" / "00000.png"))
    assert len(np.unique(painted)) > 3   # the painter's three levels, developed by the effects


def test_reference_train_passes_its_variety_to_the_renderer_and_the_card(tmp_path, monkeypatch, capsys):
    """The command with the rendering and training replaced by recorders; a bad spec is one line, nothing run."""
    from isu_validate import render
    from isu_validate.reference import training

    seen = []

    def record(space, renderer, out, workdir, n, held_out, seed, preset, **extra):
        seen.append((renderer, extra))
        return {"held_out": {"per_feature": {}}}

    monkeypatch.setattr(render, "open_renderer", lambda **kw: _Painter())
    monkeypatch.setattr(training, "train_reference", record)
    args = ["reference", "train", "--n", "10", "--held-out", "1", "--seed", "4", "--workdir", str(tmp_path / "w")]
    assert main([*args, "--sensor-effects", "mild,noise=0.02"]) == 0
    renderer, extra = seen[-1]
    assert isinstance(renderer, VariedRenderer) and renderer.variety.effects.noise == 0.02
    assert extra["variety"] == Variety.parse(None, "mild,noise=0.02", 4).describe()
    assert main([*args, "--out", str(tmp_path / "plain")]) == 0
    assert isinstance(seen[-1][0], _Painter) and not seen[-1][1]["variety"]      # off: the renderer itself
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "bad"), "--camera-jitter", "focal=2"]) == 2
    err = capsys.readouterr().err
    assert "focal must be between 0 and 0.3" in err and len(err.strip().splitlines()) == 1 and len(seen) == 2



# ---------------------------------------------------------------- several viewpoints (camera mix)
def test_a_camera_mix_sees_each_scene_through_one_of_its_rigs_seeded_and_then_jitters_it():
    scenes = [SPACE.canonical(s) for s in SPACE.sample(np.random.default_rng(1), 60)]
    mix = Variety.parse(None, None, 3, " passenger-door, passenger-side,passenger-door")
    assert mix.cameras == ("passenger-door", "passenger-side") and mix.active and mix.moves_camera
    first, again = VariedRenderer(_CameraHolder(), mix), VariedRenderer(_CameraHolder(), mix)
    picks = [first.camera_for(s)[1]["rig"] for s in scenes]
    assert picks == [again.camera_for(s)[1]["rig"] for s in scenes]               # seeded by the scene
    assert set(picks) == {"default", "passenger-door", "passenger-side"}
    assert min(picks.count(p) for p in set(picks)) >= 10                            # uniform among three
    camera, drawn = first.camera_for(scenes[0])
    assert camera.name == drawn["rig"] and "shift_m" not in drawn
    keys = {first.cache_key(s) for s in scenes}
    assert len(keys) == len(scenes) and first.inner.used[-1].name == picks[-1]     # the key follows the camera used
    # the jitter starts from the scene's rig, with the draw it had without a mix
    jittered = VariedRenderer(_CameraHolder(), Variety.parse("angle=5", None, 3, "passenger-door,passenger-side"))
    alone = VariedRenderer(_CameraHolder(), Variety.parse("angle=5", None, 3))
    for scene, pick in zip(scenes[:6], picks):
        camera, drawn = jittered.camera_for(scene)
        rig = next(r for r in jittered.rigs if r.name == pick)
        assert drawn["rig"] == pick and drawn["turn_deg"] == alone.camera_for(scene)[1]["turn_deg"]
        assert camera.hash == rig.nudged(drawn["shift_m"], drawn["turn_deg"], drawn["focal_scale"]).hash


def test_without_a_mix_the_keys_and_draws_of_earlier_sets_stay_as_they_were():
    jitter = Variety.parse("pos=0.05,angle=5,focal=0.1", "mild", 3)
    assert jitter.spec() == {"camera_jitter": "pos=0.05,angle=5,focal=0.1", "sensor_effects": jitter.effects.text,
                             "seed": 3}
    assert jitter.describe()["per_scene"].endswith("stream 1 the camera, 2 the effects")
    assert "rig" not in VariedRenderer(_CameraHolder(), jitter).camera_for(SCENES[0])[1]
    mixed = Variety.parse("pos=0.05,angle=5,focal=0.1", "mild", 3, "passenger-door")
    assert mixed.spec() == {**jitter.spec(), "camera_mix": "passenger-door"}
    assert mixed.describe()["per_scene"].endswith(", 3 the camera rig")
    assert Variety.parse(None, None, 3, "") == Variety(seed=3) and not Variety.parse(None, None, 3, "none").active


@pytest.mark.parametrize("mix, says", [("no-such-rig", "--camera-mix 'no-such-rig': no cameras rig named"),
                                       ("passenger-door,default", "'default' is the set's own camera (--camera)")])
def test_a_bad_camera_mix_is_refused_naming_the_rig_and_the_fix(mix, says):
    with pytest.raises(InputError) as raised:
        VariedRenderer(_CameraHolder(), Variety.parse(None, None, 0, mix))
    assert says in str(raised.value)


def test_reference_train_and_its_card_take_the_camera_mix(tmp_path, monkeypatch):
    from isu_validate import render
    from isu_validate.reference import training

    seen = []
    monkeypatch.setattr(render, "open_renderer", lambda **kw: _CameraHolder())
    monkeypatch.setattr(training, "train_reference", lambda *a, **extra: seen.append((a[1], extra)) or
                        {"held_out": {"per_feature": {}}})
    assert main(["reference", "train", "--n", "10", "--held-out", "1", "--seed", "4", "--workdir",
                 str(tmp_path / "w"), "--camera-mix", "passenger-door"]) == 0
    renderer, extra = seen[-1]
    assert renderer.variety.cameras == ("passenger-door",) and extra["variety"]["camera_mix"] == "passenger-door"
    assert training._variety_flags(extra["variety"]) == " --camera-mix passenger-door"
    assert "- camera mix: each scene seen through the set's camera or one of `passenger-door`" in "\n".join(
        render.variety.card_lines(extra["variety"]))
