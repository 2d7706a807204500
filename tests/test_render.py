"""The Blender renderer, with real Blender at small resolution (one warm worker for the module).

Every feature of the isu-paper space must visibly change the image, and the segmentation mask of the
object it concerns; the cache, crash recovery and the camera rig's geometry are checked too."""
from __future__ import annotations

import json
import os
import signal
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from isu_validate.protocols import RenderError
from capture.camera import camera_from_dict, load_camera
from isu_validate.render import Preset, open_renderer, render_board
from isu_validate.render.labels import INSTANCE_ID
from isu_validate.space import SpaceError, load_space

pytestmark = pytest.mark.blender

# 200x150, 2 samples, no denoiser: enough to see every feature, fast on a shared 2-core machine
TEST_PRESET = Preset("test", 0.3125, 2, False, "NONE", 2, 1, 1, 3.0, 1.5)

BASE = {"driver_gender": "MALE", "driver_emotion": "SERIOUS", "driver_height": "H2", "driver_weight": "W2",
        "phone_position": "NONE", "seat_belt": "NO", "tshirt_colour": "WHITE", "child_seat": "NO",
        "car_lights": "OFF", "external_light": "MEDIUM", "luggage": "NO", "phone_codriver_seat": "NO",
        "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}
CODRIVER_SEAT = ("phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat")
# the context in which each feature is active, and the instance whose mask it must change
# (None: it changes colour or light, checked through pixels inside `region` or over the whole image)
CONTEXT = {"child_seat": {"child": "YES", "child_seat_orientation": "FRONT_FACING"},
           "child": {"child_seat": "YES", "child_seat_orientation": "FRONT_FACING"},
           "child_seat_orientation": {"child_seat": "YES", "child": "YES"},
           "luggage": {"luggage_orientation": 60.0, "luggage_position": "BACK", "luggage_colour": "YELLOW"},
           **{f: {"luggage": "YES", "luggage_orientation": 60.0, "luggage_position": "BACK", "luggage_colour": "YELLOW"}
              for f in ("luggage_orientation", "luggage_position", "luggage_colour")}}
AFFECTS = {"driver_gender": "driver", "driver_height": "driver", "driver_weight": "driver",
           "phone_position": "phone", "seat_belt": "seat_belt", "child_seat": "child_seat", "child": "child",
           "child_seat_orientation": "child_seat", "luggage": "luggage", "luggage_orientation": "luggage",
           "luggage_position": "luggage", **{f: f for f in CODRIVER_SEAT}}   # these name their instance
REGION = {"driver_emotion": ("driver_face",), "tshirt_colour": ("driver",), "luggage_colour": ("luggage",)}


@pytest.fixture(scope="module")
def renderer(tmp_path_factory):
    root = tmp_path_factory.mktemp("render")
    # the default rig's auto-exposure is taken off: with it, a feature that brightens one part (a white
    # T-shirt) moves the whole frame's exposure, and these tests ask where each feature shows
    from dataclasses import replace
    from capture.camera import load_camera
    plain = replace(load_camera("default"), imaging=None)
    r = open_renderer(TEST_PRESET, camera=plain, channels=("seg", "depth"), cache_dir=root / "cache",
                      log_dir=root / "logs")
    yield r
    r.close()


@pytest.fixture(scope="module")
def frames(renderer, tmp_path_factory):
    """Renders by scene, memoised across the module's tests."""
    out = tmp_path_factory.mktemp("frames")
    memo = {}

    def render(scene: dict):
        key = renderer.space.key(scene)
        if key not in memo:
            result = renderer.render(scene, out / f"{len(memo):03d}.png")
            memo[key] = (cv2.imread(str(result.image)).astype(int),
                         cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED), result)
        return memo[key]
    return render


def _values(feature):
    if feature.type == "continuous":
        return [feature.low, feature.high]
    return list(feature.values)


@pytest.mark.parametrize("name", list(load_space().names))
def test_every_value_of_every_feature_changes_the_image(name, frames):
    space = load_space()
    feature = space.features[name]
    scenes = [{**BASE, **CONTEXT.get(name, {}), name: v} for v in _values(feature)]
    for scene in scenes:
        space.check(scene)
    rendered = [frames(s) for s in scenes]
    ref_img, ref_seg, _ = rendered[0]
    for scene, (img, seg, result) in zip(scenes[1:], rendered[1:]):
        changed = np.abs(img - ref_img).max(axis=2) > 12
        assert changed.sum() >= 8, f"{name}={scene[name]!r} looks like {name}={scenes[0][name]!r}"
        if name in AFFECTS:
            iid = INSTANCE_ID[AFFECTS[name]]
            moved = ((seg == iid) != (ref_seg == iid)).sum()
            # a thing hidden from this camera (the phone at the left ear, behind the head) need not show,
            # but then the renderer must say so: its feature is labelled occluded (never judged)
            assert moved >= 8 or name in result.occluded, \
                f"{name}={scene[name]!r}: the {AFFECTS[name]} mask did not change ({moved} px) and is not occluded"
        if name in REGION:
            ids = [INSTANCE_ID[part] for part in REGION[name]]
            inside = np.isin(seg, ids) | np.isin(ref_seg, ids)
            assert changed[inside].sum() >= 0.5 * changed.sum() and changed[inside].sum() >= 3, \
                f"{name}: the change is not on the {'/'.join(REGION[name])}"
    if name == "phone_position":  # ten different poses, all distinct from each other
        imgs = [r[0] for r in rendered]
        for i in range(len(imgs)):
            for j in range(i + 1, len(imgs)):
                assert (np.abs(imgs[i] - imgs[j]).max(axis=2) > 12).sum() >= 8, \
                    f"phone positions {scenes[i][name]} and {scenes[j][name]} look the same"


EVERYTHING = {**BASE, **{f: "YES" for f in CODRIVER_SEAT}, "phone_position": "P6", "luggage": "YES",
              "luggage_orientation": 90.0, "luggage_position": "BACK", "luggage_colour": "YELLOW", "seat_belt": "YES"}


def test_present_objects_are_visible_and_absent_ones_are_not(frames):
    _, seg, result = frames(EVERYTHING)
    for thing in ("driver", "seat_belt", "phone", *CODRIVER_SEAT, "luggage"):
        assert (seg == INSTANCE_ID[thing]).sum() >= 10, f"{thing} is (almost) invisible"
    # a child seat (with its child) takes the co-driver seat, so it is seen in a scene of its own
    _, seg, _ = frames({**BASE, "child_seat": "YES", "child": "YES", "child_seat_orientation": "FRONT_FACING"})
    for thing in ("child_seat", "child"):
        assert (seg == INSTANCE_ID[thing]).sum() >= 10, f"{thing} is (almost) invisible"
    _, seg0, _ = frames(BASE)
    for thing in ("phone", *CODRIVER_SEAT, "luggage", "child_seat", "child", "seat_belt"):
        assert not (seg0 == INSTANCE_ID[thing]).any(), f"{thing} shows although the scene has none"
    assert set(result.timings) >= {"update_s", "render_s", "write_s", "total_s"}
    depth = cv2.imread(str(result.channels["depth"]), cv2.IMREAD_UNCHANGED)
    assert depth.dtype == np.uint16 and 200 < np.median(depth[depth > 0]) < 3000   # millimetres in a cabin


def test_the_label_says_where_the_bottles_cap_points_as_its_pixels_do(renderer, frames):
    """The bottle lies with its base at the rig's position: its pixels run from that point (projected)
    towards the cap, which is where the label's ``up`` must point (the Euler angles read as Blender does)."""
    _, seg, result = frames(EVERYTHING)
    assert set(result.up) == set(CODRIVER_SEAT)
    ys, xs = np.nonzero(seg == INSTANCE_ID["colabottle_codriver_seat"])
    base = renderer.render_rig.project(renderer.cabin["codriver_seat"]["colabottle_codriver_seat"]["position"])[0]
    towards = np.array([xs.mean(), ys.mean()]) - base
    assert towards @ result.up["colabottle_codriver_seat"] > 0.97 * np.linalg.norm(towards)
    assert result.up["colacan_codriver_seat"][1] < -0.8                  # a standing can's top is up the frame
    assert json.loads(result.channels["label"].read_text())["up"] == result.up


def test_the_codriver_seat_objects_lie_on_the_cushion_apart_from_each_other(renderer, tmp_path):
    """From the rig's geometry as Blender builds it: each thing rests on the flat top of the passenger
    cushion (neither floating nor sunk into it), inside its flat part, clear of the backrest and of
    each other; the phone in the hand is another object."""
    seat = renderer.cabin["seats"]["passenger"]
    cx, cy, top = seat["cushion"]
    flat = seat["depth"] / 2 - 0.09, seat["width"] / 2 - 0.09   # the cushion's rounded edges are 0.09 m wide
    boxes = renderer.bounds({**BASE, **{f: "YES" for f in CODRIVER_SEAT}, "phone_position": "P9"})
    for thing in CODRIVER_SEAT:
        lo, hi = np.array(boxes[thing][0]), np.array(boxes[thing][1])
        assert abs(lo[2] - top) < 0.002, f"{thing} rests at z = {lo[2]:.4f}, not on the cushion at {top}"
        assert lo[0] >= cx - flat[0] and hi[0] <= cx + flat[0], f"{thing} spans x {lo[0]:.3f}..{hi[0]:.3f}"
        assert lo[1] >= cy - flat[1] and hi[1] <= cy + flat[1], f"{thing} spans y {lo[1]:.3f}..{hi[1]:.3f}"
        assert lo[0] > -0.18, f"{thing} reaches into the backrest (x {lo[0]:.3f})"
    for i, a in enumerate(CODRIVER_SEAT):
        for b in CODRIVER_SEAT[i + 1:]:
            gap = np.maximum(np.array(boxes[a][0]) - boxes[b][1], np.array(boxes[b][0]) - boxes[a][1]).max()
            assert gap >= 0.03, f"{a} and {b} are {gap:.3f} m apart"
    assert "phone" in boxes and boxes["phone"][0][1] > cy + flat[1]   # the hand's phone is not on that seat
    assert set(CODRIVER_SEAT).isdisjoint(renderer.bounds(BASE))


def test_the_default_camera_frames_the_tallest_drivers_head_and_shows_p8(renderer, frames):
    """The rig's framing, measured from the geometry: the head (hair included) of the tallest, heaviest
    driver stays inside the frame (its bounding box's top corner at most 2% of the height above the
    edge; the first framing cut it by ~20%), and the phone by the door (P8) is not hidden behind the
    wheel for a middle body."""
    height = renderer.render_rig.height
    for gender in ("MALE", "FEMALE"):
        box = renderer.bounds({**BASE, "driver_gender": gender, "driver_height": "H4",
                               "driver_weight": "W4"})["driver_face"]
        corners = np.array(np.meshgrid(*zip(*box))).reshape(3, -1).T      # the box's 8 corners
        top = renderer.render_rig.project(corners)[:, 1].min()
        assert top >= -0.02 * height, f"a tall {gender.lower()} driver's head is cut: its top at row {top:.1f}"
    *_, result = frames({**BASE, "phone_position": "P8"})
    assert result.visibility["phone_position"] >= 0.4 and "phone_position" not in result.occluded


def test_invalid_scene_is_refused_before_blender(renderer, tmp_path):
    with pytest.raises(SpaceError, match="co-driver seat"):
        renderer.render({**BASE, "phone_codriver_seat": "YES", "child_seat": "YES", "child": "NO",
                         "child_seat_orientation": "FRONT_FACING"}, tmp_path / "x.png")
    with pytest.raises(SpaceError, match="luggage_colour"):
        renderer.render({**BASE, "luggage": "YES", "luggage_colour": "PINK", "luggage_position": "BACK",
                         "luggage_orientation": 30.0}, tmp_path / "x.png")


def test_cache_returns_the_same_image_at_no_render_cost(renderer, tmp_path):
    scene = {**BASE, "colacan_codriver_seat": "YES", "external_light": "HIGH"}
    renderer.render(scene, tmp_path / "a.png")
    second = renderer.render({**scene, "luggage_colour": "YELLOW"}, tmp_path / "b.png")  # inactive feature
    assert second.cached and second.timings["render_s"] == 0.0
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()
    assert Path(second.channels["seg"]).is_file() and Path(second.channels["label"]).is_file()
    third = renderer.render({**scene, "colabottle_codriver_seat": "YES", "tshirt_colour": "BLACK"}, tmp_path / "c.png")
    assert not third.cached and third.timings["render_s"] > 0


def test_killed_worker_is_restarted_and_the_scene_retried(renderer, tmp_path):
    renderer.render({**BASE, "tshirt_colour": "BLACK"}, tmp_path / "warm.png")  # worker up
    pid = renderer.worker_pid
    scene = {**BASE, "driver_height": "H4", "external_light": "LOW"}   # not cached yet
    worker = renderer._worker
    read_reply = worker._read

    def die_before_replying(timeout_s):
        # the request has been sent: kill the worker while it works on it (no timing race)
        worker._read = read_reply
        os.killpg(pid, signal.SIGKILL)
        return read_reply(timeout_s)

    worker._read = die_before_replying
    result = renderer.render(scene, tmp_path / "after_crash.png")
    assert result.image.is_file() and renderer.worker_pid != pid


def test_an_output_that_cannot_be_written_is_a_render_error_cached_or_not(renderer, tmp_path, monkeypatch):
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    scene = {**BASE, "driver_height": "H2", "colacan_codriver_seat": "YES"}
    renderer.render(scene, tmp_path / "first.png")                  # now in the cache
    with pytest.raises(RenderError, match="could not write"):       # was a bare FileExistsError
        renderer.render(scene, blocked / "cached.png")
    monkeypatch.setattr(renderer, "cache", None)
    with pytest.raises(RenderError, match="could not write"):
        renderer.render(scene, blocked / "rendered.png")
    assert renderer.render(scene, tmp_path / "after.png").image.is_file()


def test_render_error_after_the_retry_fails(tmp_path):
    r = open_renderer(TEST_PRESET, log_dir=tmp_path, timeout_s=0.05)
    try:
        r._ensure_worker()   # start-up has its own, longer limit
        t = time.perf_counter()
        with pytest.raises(RenderError, match="failed twice"):
            r.render(BASE, tmp_path / "x.png")
        assert time.perf_counter() - t < 120
        assert r.log_path.stat().st_size > 0   # Blender's console output went to the log, not the terminal
    finally:
        r.close()


DOT = (0.3, 0.6)   # where the dot sits on the board image, as fractions of its width and height


def _dot_board(tmp_path, px=400):
    """A white board with one black dot off its centre (so a flipped texture would be caught)."""
    img = np.full((px, px, 3), 255, np.uint8)
    cv2.circle(img, (round(DOT[0] * px), round(DOT[1] * px)), px // 10, (0, 0, 0), -1)
    path = tmp_path / "dot.png"
    cv2.imwrite(str(path), img)
    return path


@pytest.mark.parametrize("distorted", [False, True])
def test_a_known_cabin_point_renders_where_the_rig_projects_it(tmp_path, distorted):
    rig = load_camera().to_dict()
    for table in ("exposure", "response", "noise", "colour"):   # a plain camera: the dot's level stays put
        rig.pop(table, None)
    rig["image"] = {"width": 400, "height": 300}
    rig["intrinsics"].update(fx=192.0, fy=188.0 if distorted else 192.0, cx=208.3, cy=143.6)
    if distorted:
        rig["intrinsics"].update(model="opencv8", distortion=[-0.28, 0.07, 0.001, -0.002, 0.0])
    cam = camera_from_dict(rig, "test rig")
    size = 0.2
    centre = cam.t + cam.R[:, 2] * 0.6 + cam.R[:, 0] * 0.12 + cam.R[:, 1] * 0.05  # 0.6 m ahead, off-axis
    R_board = cam.R                                     # board axes = camera axes: it faces the camera
    origin = centre - R_board @ np.array([size / 2, size / 2, 0.0])
    preset = Preset("test", 1.0, 2, False, "NONE", 1, 1, 0, 3.0, 1.0)
    r = open_renderer(preset, camera=cam, log_dir=tmp_path)
    try:
        result = render_board(_dot_board(tmp_path), (size, size), (R_board, origin), tmp_path / "board.png", renderer=r)
    finally:
        r.close()
    img = cv2.imread(str(result.image), cv2.IMREAD_GRAYSCALE)
    assert img.shape == (300, 400)
    # the board: the largest bright region, holes filled; the dot: darkness inside it, away from its rim
    n, labels, stats, _ = cv2.connectedComponentsWithStats((img > 200).astype(np.uint8))
    board = (labels == 1 + np.argmax(stats[1:, cv2.CC_STAT_AREA])).astype(np.uint8)
    contours, _ = cv2.findContours(board, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    filled = cv2.drawContours(np.zeros_like(board), contours, -1, 1, -1)
    inner = cv2.erode(filled, np.ones((7, 7), np.uint8)) > 0
    weight = np.where(inner, np.clip(230.0 - img, 0, None), 0.0)
    ys, xs = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    found = np.array([(xs * weight).sum(), (ys * weight).sum()]) / weight.sum()
    expected = cam.project(origin + R_board @ np.array([DOT[0] * size, DOT[1] * size, 0.0]))[0]
    assert np.linalg.norm(found - expected) < 0.6, f"dot at {found}, rig projects it to {expected}"


def test_an_asset_named_in_the_cabin_rig_replaces_the_procedural_part(tmp_path):
    from isu_validate.paths import rigs_dir
    # a 0.3 x 0.5 x 0.6 m box as an OBJ file (y up, as OBJ files are), standing in for a scanned suitcase
    verts = [(x, y, z) for x in (-0.15, 0.15) for z in (-0.25, 0.25) for y in (0.0, 0.6)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    (tmp_path / "box.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in verts)
                                      + "".join("f " + " ".join(map(str, f)) + "\n" for f in faces))
    rig = tmp_path / "cabin.toml"
    rig.write_text((rigs_dir() / "cabins" / "default.toml").read_text()
                   + '\n[assets.luggage]\nfile = "box.obj"\n')
    scene = {**BASE, "luggage": "YES", "luggage_orientation": 30.0, "luggage_position": "PASSENGER",
             "luggage_colour": "YELLOW"}
    r = open_renderer(TEST_PRESET, cabin=rig, channels=("seg",), log_dir=tmp_path)
    try:
        result = r.render(scene, tmp_path / "asset.png")
    finally:
        r.close()
    seg = cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED)
    assert (seg == INSTANCE_ID["luggage"]).sum() > 200


def test_render_command_writes_frames_labels_and_a_contact_sheet(tmp_path):
    import argparse
    import json

    from isu_validate.commands import render as command
    parser = argparse.ArgumentParser()
    command.register(parser.add_subparsers())
    args = parser.parse_args(["render", "--random", "2", "--seed", "3", "--out", str(tmp_path / "frames"),
                              "--preset", "draft", "--channels", "seg"])
    assert args.func(args) == 0
    frames = sorted((tmp_path / "frames").glob("scene-*[0-9].png"))
    assert len(frames) == 2 and (tmp_path / "frames" / "contact_sheet.png").is_file()
    label = json.loads(frames[0].with_suffix(".label.json").read_text())
    assert label["scene"] == json.loads(frames[0].with_suffix(".scene.json").read_text())
    assert cv2.imread(str(frames[0])).shape == (240, 320, 3)   # draft: half the rig's resolution
    scene_file = tmp_path / "one.json"
    scene_file.write_text(json.dumps({**BASE, "phone_codriver_seat": "YES", "phone_position": "P2"}))
    args = parser.parse_args(["render", str(scene_file), "--out", str(tmp_path / "one.png"), "--preset", "draft"])
    assert args.func(args) == 0 and (tmp_path / "one.png").is_file()


def test_bench_render_reports_speed_and_error_per_preset(tmp_path, capsys):
    import argparse
    import json

    from isu_validate.bench.render import register_bench
    parser = argparse.ArgumentParser()
    register_bench(parser.add_subparsers())
    # a command SUT that answers from the image's brightness: some answers may flip with the preset
    sut = tmp_path / "sut.py"
    sut.write_text("import json, sys, cv2\nr = json.load(sys.stdin)\nm = cv2.imread(r['image']).mean()\n"
                   "print(json.dumps({'answers': {q['key']: q['options'][int(m) % len(q['options'])] "
                   "for q in r['questions']}}))\n")
    args = parser.parse_args(["render", "--scenes", "1", "--repeat", "1", "--reference-samples", "2",
                              "--presets", "draft", "--out", str(tmp_path),
                              "--sut", f"command:{sys.executable} {sut}"])
    assert args.func(args) == 0
    row = json.loads((tmp_path / "bench.json").read_text())["presets"][0]
    assert row["preset"] == "draft" and row["s_per_frame"]["min"] > 0 and "draft" in capsys.readouterr().out
    # the figures are those of the frames it wrote: the draft frame (upscaled) against the reference
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity
    [reference] = [cv2.imread(str(p)) for p in tmp_path.glob("reference-*.png")]
    draft = cv2.imread(str(tmp_path / "draft-0.png"))
    draft = cv2.resize(draft, (reference.shape[1], reference.shape[0]), interpolation=cv2.INTER_CUBIC)
    assert row["psnr_db"] == pytest.approx(peak_signal_noise_ratio(reference, draft, data_range=255))
    assert row["ssim"] == pytest.approx(structural_similarity(reference, draft, channel_axis=2, data_range=255))
    assert 10 < row["psnr_db"] < 60 and row["ssim"] < 1.0  # a real difference, not a frame against itself
    assert row["ssim_per_scene"] == [pytest.approx(row["ssim"], abs=1e-5)] and row["ssim_floor"] is None  # draft: none
    # the SUT answers option (mean brightness mod number of options): unchanged where both frames agree
    space = load_space()
    scene = space.sample(np.random.default_rng(json.loads((tmp_path / "bench.json").read_text())["seed"]), 1)[0]
    draft_mean, reference_mean = (int(cv2.imread(str(p)).mean()) for p in
                                  (tmp_path / "draft-0.png", *tmp_path.glob("reference-*.png")))
    same = [draft_mean % len(q.options) == reference_mean % len(q.options) for q in space.questions(scene)]
    assert row["sut_unchanged"] == pytest.approx(sum(same) / len(same))


def test_charuco_corners_render_where_the_rig_projects_them(tmp_path):
    """The seam the calibration loop uses: a ChArUco image on a board in the cabin, detected in the
    render, lands where the rig projects the board's corners."""
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    board = cv2.aruco.CharucoBoard((7, 5), 0.04, 0.03, dictionary)
    cv2.imwrite(str(tmp_path / "charuco.png"), board.generateImage((1400, 1000), marginSize=0))
    cam = load_camera()
    R = cam.R
    origin = cam.t + R[:, 2] * 0.42 - R @ np.array([0.14, 0.10, 0.0])
    # like the calibration preset, with fewer samples and direct light only: fast, still noise-free enough
    preset = Preset("test-calibration", 1.0, 16, False, "NONE", 0, 0, 0, 3.0, 1.5)
    result = render_board(tmp_path / "charuco.png", (0.28, 0.20), (R, origin), tmp_path / "board.png",
                          camera=cam, preset=preset)
    corners, ids, _, _ = cv2.aruco.CharucoDetector(board).detectBoard(cv2.imread(str(result.image)))
    assert ids is not None and len(ids) >= 12
    projected = cam.project(origin + board.getChessboardCorners()[ids.ravel()] @ R.T)
    rms = np.sqrt(((corners.reshape(-1, 2) - projected) ** 2).sum(axis=1).mean())
    assert rms < 0.2, f"ChArUco corners {rms:.2f} px RMS from the rig's projection"
