"""The pairs layout, the alignment aid, and capture into a pair (replay source; one Blender stand-in)."""
import json
import re
import shutil

import cv2
import numpy as np
import pytest

from capture.alignment import align
from isu_validate.cli import main
from isu_validate.pairs import PairsDir, PairsError
from isu_validate.paths import resolve_rig


def scene_image(w=320, h=240) -> np.ndarray:
    img = np.full((h, w, 3), 90, np.uint8)
    cv2.rectangle(img, (60, 50), (160, 170), (200, 60, 50), -1)
    cv2.circle(img, (230, 120), 40, (40, 200, 220), -1)
    cv2.line(img, (10, 220), (300, 200), (250, 250, 250), 3)
    return img


def moved(img: np.ndarray, dx: float, dy: float, gain=0.8, noise=6.0, seed=0) -> np.ndarray:
    m = np.float32([[1, 0, dx], [0, 1, dy]])
    out = cv2.warpAffine(img, m, img.shape[1::-1], borderMode=cv2.BORDER_REPLICATE).astype(np.float32) * gain
    out += np.random.default_rng(seed).normal(0, noise, img.shape)
    return np.clip(out, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("dx,dy", [(0, 0), (6, -4), (15, 10), (-25, 20)])
def test_the_shift_is_measured_in_frame_pixels_whatever_the_exposure(dx, dy):
    result, image = align(scene_image(), moved(scene_image(), dx, dy))
    assert result.shift_px == pytest.approx(np.hypot(dx, dy), abs=1.0)
    assert image.shape[1:] == (640, 3) and image.shape[0] > 240   # a banner, then edges and ghost side by side
    expected = "aligned" if np.hypot(dx, dy) <= 0.012 * 400 else "check" if np.hypot(dx, dy) <= 0.035 * 400 else "off"
    assert result.verdict == expected


def test_a_smaller_render_is_compared_at_the_frame_size():
    frame = cv2.resize(moved(scene_image(), 6, -4), (640, 480), interpolation=cv2.INTER_LINEAR)
    result, _ = align(scene_image(), frame)
    assert result.shift_px == pytest.approx(2 * np.hypot(6, 4), abs=1.5) and result.size == (640, 480)
    assert result.edge_distance_px > 2.0


def test_black_and_saturated_frames_and_odd_shapes_explain_themselves():
    for flat in (np.zeros((240, 320, 3), np.uint8), np.full((240, 320, 3), 255, np.uint8)):
        result, image = align(scene_image(), flat)
        assert result.edge_distance_px is None and result.verdict == "off"
        assert "no edges in the frame" in result.message and image.shape[0] > 240
    result, _ = align(scene_image(), moved(cv2.resize(scene_image(), (320, 320)), 0, 0))
    assert "different shapes" in result.message


def make_pair(root, render: np.ndarray):
    sample = root / "S01"
    sample.mkdir(parents=True)
    cv2.imwrite(str(sample / "sim.png"), render)
    (sample / "scene.json").write_text(json.dumps({"space": "isu-paper", "scene": {"seat_belt": "YES"}}))
    return sample


def recorded_session(folder, frames):
    folder.mkdir()
    for i, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"frame_{i:04d}.png"), frame)
        (folder / f"frame_{i:04d}.json").write_text(json.dumps({"device": "test", "exposure_us": 8000, "iso": 100,
                                                                "timestamp": "2026-11-22T10:00:00+00:00"}))
    return folder


def test_capture_shoot_into_a_pair_appends_frames_with_sidecars_and_alignment(tmp_path, capsys):
    render = scene_image()
    sample = make_pair(tmp_path / "pairs", render)
    rec = recorded_session(tmp_path / "rec", [moved(render, 2, 1), moved(render, 30, 0, seed=1)])
    assert main(["capture", "shoot", "--source", f"replay:{rec}", "--frames", "2", "--pair", str(sample)]) == 0
    err = capsys.readouterr().err
    assert "frame_0000.png: edge distance" in err and ": off." in err.split("frame_0001.png")[1]
    meta = json.loads((sample / "real" / "frame_0000.json").read_text())
    assert meta["exposure_us"] == 8000 and meta["alignment"]["verdict"] == "aligned"
    assert meta["alignment"]["aid_image"] == "align/frame_0000.png" and (sample / "align" / "frame_0000.png").is_file()
    # a second session numbers on; nothing is overwritten, and the aid images never count as frames
    assert main(["capture", "shoot", "--source", f"replay:{rec}", "--frames", "1", "--pair", str(sample)]) == 0
    pair = PairsDir(tmp_path / "pairs").sample("S01")
    assert [p.name for p in pair.real_frames()] == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    assert (sample / "real" / "session_0002.json").is_file()
    assert main(["capture", "align", "--source", f"replay:{rec}", "--frames", "2", "--pair", str(sample)]) == 0
    assert capsys.readouterr().out.count("frame ") == 2 and (sample / "align" / "live.png").is_file()
    assert main(["capture", "shoot", "--source", "standin", "--out", str(tmp_path / "x")]) == 2
    assert "--pair" in capsys.readouterr().err


def test_the_pairs_layout_is_read_in_one_place(tmp_path):
    root = tmp_path / "pairs"
    with pytest.raises(PairsError, match="does not exist"):
        PairsDir(root).samples()
    sample = make_pair(root, scene_image())
    (sample / "real").mkdir()
    pairs = PairsDir(root)
    assert pairs.sample("S01").scene() == {"seat_belt": "YES"}                 # a run's label
    (sample / "scene.json").write_text(json.dumps({"seat_belt": "NO"}))
    assert pairs.sample("S01").scene() == {"seat_belt": "NO"}                  # a bare scene
    with pytest.raises(PairsError, match="no real images.*capture shoot --pair"):
        pairs.role_images("real")
    with pytest.raises(PairsError, match="stylize --pairs"):
        pairs.role_images("nst")
    s = pairs.sample("S01")
    s.record_vote("ann", True)
    s.record_vote("bob", False)
    s.record_vote("ann", False)   # a second vote replaces the first
    assert s.votes() == {"ann": False, "bob": False}
    s.votes_file.write_text("{broken")
    with pytest.raises(PairsError, match="fix or delete"):
        s.votes()
    (sample / "scene.json").write_text("[1, 2]")
    with pytest.raises(PairsError, match="not a JSON object"):
        s.label()


@pytest.mark.blender
@pytest.mark.slow
def test_a_stand_in_render_is_captured_into_a_pair_and_aligns(tmp_path, capsys):
    """The pair's scene rendered by Blender through the stand-in rig, sunset light and noise."""
    from isu_validate.render import open_renderer
    from isu_validate.space import load_space
    space = load_space()
    scene = space.sample(np.random.default_rng(4), 1)[0]
    sample = tmp_path / "pairs" / "S01"
    sample.mkdir(parents=True)
    with open_renderer("draft", log_dir=tmp_path, space=space) as renderer:
        renderer.render(scene, sample / "sim.png")
    (sample / "scene.json").write_text(json.dumps({"space": space.name, "scene": space.canonical(scene)}))
    shutil.copyfile(resolve_rig("cameras", "default"), sample / "camera.toml")   # as recreate copies it
    assert main(["capture", "shoot", "--source", "standin", "--frames", "2", "--pair", str(sample)]) == 0
    meta = json.loads((sample / "real" / "frame_0001.json").read_text())
    assert meta["stand_in"] is True and meta["camera_rig"] == "standin" and meta["environment"] == "sunset"
    frames = [cv2.imread(str(sample / "real" / f"frame_000{i}.png")) for i in (0, 1)]
    assert frames[0].shape == cv2.imread(str(sample / "sim.png")).shape
    assert np.abs(frames[0].astype(int) - frames[1]).mean() > 1.0     # each frame its own noise
    # the stand-in rig looks 5.4° lower and sits 4.5 cm lower than the default one (0.5-1 m from what it
    # sees: 2.5-5° more), and 3.3° further to its left but 1.5 cm to its right (1-2° less): the aid says to
    # tilt up and turn right by about that
    aid = meta["alignment"]
    assert aid["edge_distance_px"] < 12 and aid["verdict"] == "off"
    assert 5.0 < -aid["tilt_deg"] < 12.0 and 0.5 < aid["pan_deg"] < 5.0, aid
    assert re.match(r"turn \d\.\d° right, tilt \d+\.\d° up", aid["advice"])
