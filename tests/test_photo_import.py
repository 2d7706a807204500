"""``capture import`` (photos from any camera: sidecars from EXIF, pixels untouched) and ``--chart-box``
(a chart the user points at). Photos here are written by Pillow with the EXIF a camera writes; the real
photographs are in tests/test_real_photos.py. Hard cases: no EXIF, a RAW file, a corrupt photo, two photos
of one name, a list of exposure times of the wrong length, a box outside the frame."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from capture.camera import load_camera
from capture.camera_model import chart, synthetic
from capture.camera_model.apply import apply
from capture.photo_import import FULL_FRAME_DIAGONAL_MM, ImportFailed, import_photos
from isu_validate.cli import main

REAL = Path(__file__).parent / "data" / "real" / "opencv_charuco_tutorial"


def photo(path: Path, exposure_s=None, iso=None, taken=None, mode=None, focal_35=None, seed=0, size=(160, 120)):
    """A JPEG with the EXIF tags a camera writes (Exif sub-IFD: ExposureTime, ISO, DateTimeOriginal...)."""
    from fractions import Fraction

    from PIL.TiffImagePlugin import IFDRational
    rng = np.random.default_rng(seed)
    image = Image.fromarray(rng.integers(20, 230, (size[1], size[0], 3), dtype=np.uint8))
    exif = Image.Exif()
    exif[0x010F], exif[0x0110] = "PhoneCo", "Pocket 9"
    sub = {}
    if exposure_s is not None:
        f = Fraction(exposure_s).limit_denominator(100000)
        sub[0x829A] = IFDRational(f.numerator, f.denominator)
    if iso is not None:
        sub[0x8827] = iso
    if taken is not None:
        sub[0x9003] = taken
    if mode is not None:
        sub[0xA402] = mode
    if focal_35 is not None:
        sub[0xA405] = focal_35
    sub[0x829D] = IFDRational(18, 10)
    sub[0x920A] = IFDRational(42, 10)
    exif.get_ifd(0x8769).update(sub)
    image.save(path, "JPEG", exif=exif, quality=92)
    return path


def sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_bracket_and_a_later_photo_become_two_folders_with_sidecars_and_unchanged_pixels(tmp_path, capsys):
    shots = tmp_path / "dcim"
    shots.mkdir()
    for i, t in enumerate((1 / 100, 1 / 50, 1 / 25)):   # a bracket one second apart, manual
        photo(shots / f"IMG_{i}.jpg", t, 200, f"2026:11:27 10:00:0{i}", mode=1, seed=i)
    photo(shots / "IMG_9.jpg", 1 / 60, 400, "2026:11:27 12:00:00", mode=0, focal_35=26, seed=9)   # two hours on
    assert main(["capture", "import", str(shots), "--out", str(tmp_path / "imp")]) == 0
    out = capsys.readouterr()
    assert "set_01: 3 frame(s) from PhoneCo Pocket 9, exposure 0.01, 0.02, 0.04 s, ISO 200, manual" in out.out
    assert "next: isu-validate exposure fit" in out.err
    bracket = sorted((tmp_path / "imp" / "set_01").glob("*.jpg"))
    assert [p.name for p in bracket] == ["IMG_0.jpg", "IMG_1.jpg", "IMG_2.jpg"]
    for i, frame in enumerate(bracket):
        assert sha(frame) == sha(shots / frame.name)            # the camera's bytes, unchanged
        meta = json.loads(frame.with_suffix(".json").read_text())
        assert meta["exposure_us"] == pytest.approx([10000, 20000, 40000][i])
        assert meta["iso"] == 200 and meta["auto_exposure"] is False and meta["sequence"] == i
        assert meta["f_number"] == pytest.approx(1.8) and meta["focal_length_mm"] == pytest.approx(4.2)
        assert meta["timestamp"] == f"2026-11-27T10:00:0{i}" and meta["sha256"] == sha(frame)
        assert meta["from_command_line"] == [] and "stand_in" not in meta
    later = json.loads((tmp_path / "imp" / "set_02" / "IMG_9.json").read_text())
    assert later["auto_exposure"] is True and later["iso"] == 400
    cam = load_camera(tmp_path / "imp" / "set_02" / "camera.toml")
    assert (cam.width, cam.height) == (160, 120) and not cam.registered
    assert cam.fx == pytest.approx(26 * 200 / FULL_FRAME_DIAGONAL_MM)      # 35 mm equivalent over the diagonal
    assert "not calibrated" in cam.calibration["intrinsics"]
    assert "placeholder" in load_camera(tmp_path / "imp" / "set_01" / "camera.toml").calibration["intrinsics"]
    # exposure fit reads the imported frames as a bracket (the sidecars are what it needs)
    from capture.camera_model import frames as frames_mod
    from capture.camera_model.response_fit import bracket as bracket_of
    loaded = frames_mod.load([tmp_path / "imp" / "set_01"])
    assert not loaded.excluded and [f.product for f in bracket_of(loaded.frames)] == pytest.approx(
        [20000, 40000, 80000])


def test_photos_without_exif_name_the_field_and_the_option_that_gives_it(tmp_path, capsys):
    assert main(["capture", "import", str(REAL), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "img_00.jpg: EXIF has no ExposureTime; give it with --exposure-us MICROSECONDS" in err
    assert main(["capture", "import", str(REAL), "--out", str(tmp_path / "b"), "--exposure-us", "10000"]) == 2
    assert "EXIF has no ISOSpeedRatings; give it with --iso" in capsys.readouterr().err
    assert main(["capture", "import", str(REAL), "--out", str(tmp_path / "c"), "--exposure-us", "1,2"]) == 2
    assert "--exposure-us gives 2 values for 4 photos" in capsys.readouterr().err
    assert main(["capture", "import", str(REAL), "--out", str(tmp_path / "d"), "--exposure-us", "10000",
                 "--iso", "100", "--auto-exposure"]) == 0
    meta = json.loads((tmp_path / "d" / "set_01" / "img_03.json").read_text())
    assert meta["exposure_us"] == 10000 and meta["iso"] == 100 and meta["auto_exposure"] is True
    assert meta["from_command_line"] == ["exposure_us", "iso", "auto_exposure"]
    assert sha(tmp_path / "d" / "set_01" / "img_03.jpg") == sha(REAL / "img_03.jpg")


def test_exif_wins_over_the_command_line_and_a_photo_without_exposure_mode_is_a_manual_bracket(tmp_path):
    p = photo(tmp_path / "a.jpg", 1 / 8, 100, "2026:01:01 00:00:00")
    result = import_photos([p], tmp_path / "out", exposure_us=5.0, iso=800)
    meta = json.loads((tmp_path / "out" / "set_01" / "a.json").read_text())
    assert meta["exposure_us"] == pytest.approx(125000) and meta["iso"] == 100 and meta["from_command_line"] == []
    assert meta["auto_exposure"] is False and "--auto-exposure" in meta["note"] and result.notes


def test_raw_corrupt_and_clashing_photos_are_refused_before_anything_is_written(tmp_path):
    (tmp_path / "IMG_1.CR2").write_bytes(b"II*\x00")
    with pytest.raises(ImportFailed, match=r"IMG_1.CR2 is a RAW file: .*import the JPEGs"):
        import_photos([tmp_path / "IMG_1.CR2"], tmp_path / "out")
    (tmp_path / "broken.jpg").write_bytes(b"\xff\xd8 not really")
    with pytest.raises(ImportFailed, match="broken.jpg cannot be read as an image"):
        import_photos([tmp_path / "broken.jpg"], tmp_path / "out")
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        photo(tmp_path / d / "same.jpg", 0.01, 100, "2026:01:01 00:00:0" + ("1" if d == "a" else "2"))
    with pytest.raises(ImportFailed, match="have the same name and belong to one burst"):
        import_photos([tmp_path / "a", tmp_path / "b"], tmp_path / "out")
    assert not (tmp_path / "out").exists()
    import_photos([tmp_path / "a"], tmp_path / "out")
    before = sorted(p.name for p in (tmp_path / "out").rglob("*"))
    with pytest.raises(ImportFailed, match=r"set_01/same.jpg already exists; import into a new --out folder"):
        import_photos([tmp_path / "a"], tmp_path / "out")                  # a second import: nothing overwritten
    assert sorted(p.name for p in (tmp_path / "out").rglob("*")) == before
    with pytest.raises(Exception, match="does not exist"):
        import_photos([tmp_path / "nothing.jpg"], tmp_path / "out")


def test_phone_photos_imported_into_a_pair_reach_agree_as_real_frames(tmp_path, capsys):
    from tests.pairs_kit import TRUTH, WRONG, fixed_sut, make_sample, space_file
    sample = make_sample(tmp_path / "pairs", "S01", [True])          # a stand-in taken before
    photo(tmp_path / "p.jpg", 1 / 30, 800, "2026:01:01 00:00:00", mode=0)
    assert main(["capture", "import", str(tmp_path / "p.jpg"), "--pair", str(sample)]) == 0
    meta = json.loads((sample / "real" / "frame_0001.json").read_text())
    assert meta["frame"] == "frame_0001.jpg" and meta["iso"] == 800 and not (sample / "real" / "camera.toml").exists()
    sut = fixed_sut(tmp_path, {"S01/sim.png": TRUTH, "S01/real/frame_0000.png": TRUTH,
                               "S01/real/frame_0001.jpg": WRONG})
    out = tmp_path / "agree"
    assert main(["agree", str(tmp_path / "pairs"), "--sut", sut, "--space", str(space_file(tmp_path)), "--out",
                 str(out), "--no-realism", "--repeats", "1"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["stand_in_frames"], summary["real_frames"]) == (1, 1)   # the photo counts as a real capture
    assert summary["by_provenance"]["real"]["agreement_rate"] == 0.0


# --------------------------------------------------------------------------- a chart the user points at

def _patch_area(corners: np.ndarray) -> np.ndarray:
    """The patch area's corners inside a synthetic chart placed at ``corners`` (chart_image: 60 px patches,
    12 px gaps and margins)."""
    import cv2
    h, w = chart.chart_image().shape[:2]
    hom = cv2.getPerspectiveTransform(np.float32([[0, 0], [w, 0], [w, h], [0, h]]), np.float32(corners))
    inner = np.float32([[[12, 12], [w - 12, 12], [w - 12, h - 12], [12, h - 12]]])
    return cv2.perspectiveTransform(inner, hom)[0].astype(float)


def test_parse_box_takes_a_rectangle_or_four_corners_and_refuses_anything_else():
    np.testing.assert_allclose(chart.parse_box("10,20,60,40"), [[10, 20], [70, 20], [70, 60], [10, 60]])
    assert chart.parse_box("1,2, 3,4, 5,6, 1,8").shape == (4, 2)
    for bad in ("10,20,60", "a,b,c,d", "10,20,-5,40", "0,0,0,0,0,0,0,0"):
        with pytest.raises(Exception, match="--chart-box"):
            chart.parse_box(bad)


def test_a_small_tilted_chart_no_detector_finds_is_read_where_the_user_points(tmp_path, capsys):
    import cv2
    # 48 px wide, ~1/13 of the frame (the real Passport of frobisher_001 is ~1/15): neither detector finds it
    corners = np.array([[300.0, 200.0], [348.0, 203.0], [347.0, 234.0], [298.0, 232.0]])
    truth = synthetic.camera().with_part(noise=None)
    real, _ = apply(synthetic.chart_scene(np.random.default_rng(3), corners=corners), truth, seed=0)
    path = tmp_path / "small.png"
    cv2.imwrite(str(path), cv2.cvtColor(real, cv2.COLOR_RGB2BGR))
    out = tmp_path / "ccm.json"
    assert main(["exposure", "colour", "--real", str(path), "--sim", "reference", "--out", str(out)]) == 2
    assert "or point at the chart you see: --chart-box X,Y,W,H" in capsys.readouterr().err
    box = ",".join(f"{v:.1f}" for v in _patch_area(corners).ravel())
    assert main(["exposure", "colour", "--real", str(path), "--sim", "reference", "--out", str(out),
                 "--chart-box", box]) == 0
    report = json.loads(out.read_text())
    assert report["detector"]["real"] == "box" and report["patches"]["used"] >= 22
    assert report["de2000_after"]["mean"] < 3 < report["de2000_before"]["mean"]
    with pytest.raises(Exception, match="reaches outside the 640x480 frame"):
        chart.find(real, "auto", "small.png", chart.parse_box("600,400,80,60"))


def test_exposure_chart_poses_the_virtual_chart_where_the_user_points(tmp_path):
    """``exposure chart --chart-box``: the chart's pose in the cabin from the box, as from a detection."""
    import cv2
    from capture.camera_model import virtual_chart
    rig = load_camera("default")
    pitch = virtual_chart.DEFAULT_PITCH_M
    texture = virtual_chart.texture()
    th, tw = texture.shape[:2]
    m_per_px = pitch / (virtual_chart.PATCH_PX + virtual_chart.GAP_PX)
    R_cam, t_cam = np.eye(3), np.array([-0.12, -0.08, 0.9])            # facing the camera, 0.9 m away

    def to_image(px):    # texture pixels -> frame pixels through the rig's lens
        board = np.column_stack([np.asarray(px, float) * m_per_px, np.zeros(len(px))])
        return rig.project_camera(board @ R_cam.T + t_cam)

    outline = to_image([[0, 0], [tw, 0], [tw, th], [0, th]])
    hom = cv2.getPerspectiveTransform(np.float32([[0, 0], [tw, 0], [tw, th], [0, th]]), np.float32(outline))
    frame = cv2.warpPerspective(texture, hom, (rig.width, rig.height), borderValue=(90, 90, 90))
    g = virtual_chart.GAP_PX
    corners = to_image([[g, g], [tw - g, g], [tw - g, th - g], [g, th - g]])
    R, t, how = virtual_chart.locate(frame, rig, pitch, box=corners)
    assert how == "box"
    np.testing.assert_allclose(t, rig.R @ t_cam + rig.t, atol=0.01)     # within 1 cm at 0.9 m
    assert np.degrees(np.arccos(np.clip((np.trace(R.T @ rig.R @ R_cam) - 1) / 2, -1, 1))) < 2
