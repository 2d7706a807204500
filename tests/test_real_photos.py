"""Acceptance on public real photographs (tests/data/real/README.md): the product beside OpenCV and
colour-science on the same photos.

- OpenCV contrib's ChArUco tutorial photos (vendored, Apache-2.0): four phone views that do not determine
  the intrinsics. ``calibrate`` must say so with the intervals and refuse to write a camera file without
  ``--force``; on the same detections its solution and OpenCV's must agree within their uncertainty, and
  OpenCV's published calibration must fall inside the product's 95% intervals.
- colour-hdri's ``frobisher_001`` bracket (not vendored: no licence stated; skipped until fetched): DSLR
  JPEGs through ``capture import``, ``exposure fit`` and ``exposure colour --chart-box``, against OpenCV's
  CalibrateDebevec and colour-science's own colour correction."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from isu_validate.cli import main

DATA = Path(__file__).parent / "data" / "real"
CHARUCO = DATA / "opencv_charuco_tutorial"
BOARD = "charuco:5x7:0.04:0.02:DICT_6X6_250"
SHA256 = {"img_00.jpg": "ecb8988b5aef9c1965a50a5a5b95664697554b3401504a987d1d0e722c15d0d1",
          "img_01.jpg": "12eddb0bd4c67cc45ad00f3eec7870241eb19843173e0f212eee7e70ee5c3d1e",
          "img_02.jpg": "11f9776eb87b9f01f66eea60d844f3ea4401cef64bb4115588d5dcde440daf3b",
          "img_03.jpg": "ac47f92fa79ded736efe822b975fe4cd8fd10d94f41407e47cf6e3e6a9cfed92"}
FROBISHER = DATA / "frobisher_001"
FETCH = ("git clone --depth 1 https://github.com/colour-science/colour-hdri-tests-datasets /tmp/chtd && mkdir -p "
         "tests/data/real/frobisher_001 && cp /tmp/chtd/frobisher_001/*.jpg tests/data/real/frobisher_001/")
PASSPORT_BOX = "404,212.5,37,22"     # the Passport's ColorChecker 24 in IMG_2601.jpg, read off the photo by eye
needs_frobisher = pytest.mark.skipif(not (FROBISHER / "IMG_2601.jpg").is_file(),
                                     reason=f"frobisher_001 is not vendored (no licence stated); fetch it: {FETCH}")


def test_the_vendored_photos_are_opencvs_bytes_with_their_licence():
    for name, digest in SHA256.items():
        assert hashlib.sha256((CHARUCO / name).read_bytes()).hexdigest() == digest
    assert "Apache License" in (CHARUCO / "LICENSE").read_text() and "b042744" in (CHARUCO / "SOURCE.md").read_text()


@pytest.fixture(scope="module")
def calibration():
    from isu_validate.bench.real import calibration_rows
    return calibration_rows(CHARUCO, BOARD, CHARUCO / "tutorial_camera_charuco.yml")


def test_the_product_and_opencv_agree_within_their_uncertainty_on_the_same_detections(calibration):
    rows = {(r["model"], r["tool"].split()[0]): r for r in calibration}
    for model in ("pinhole", "opencv8"):
        ours, cv = rows[(model, "isu-validate")], rows[(model, "OpenCV")]
        assert ours["views"] == cv["views"] == 4 and ours["corners"] >= 90
        assert ours["rms_px"] == pytest.approx(cv["rms_px"], abs=0.03)     # 0.18 vs 0.19-0.20 px
        for i, k in enumerate(("fx", "fy", "cx", "cy")):
            joint = np.hypot(ours["sd"][i], cv["sd"][i])
            assert abs(ours[k] - cv[k]) < 2.5 * joint, (model, k, ours[k], cv[k], joint)
        assert not ours["determined"]
    # OpenCV's published calibration of these photos (5 terms, 2021) lies inside the product's 95% intervals
    published, ours = rows[("opencv5", "published:")], rows[("opencv8", "isu-validate")]
    for i, k in enumerate(("fx", "fy", "cx", "cy")):
        assert abs(published[k] - ours[k]) < 1.96 * ours["sd"][i], k


def test_calibrate_refuses_intrinsics_the_views_do_not_determine_unless_forced(tmp_path, capsys):
    from capture.camera import read_toml
    out = tmp_path / "phone.toml"
    assert main(["calibrate", str(CHARUCO), "--board", BOARD, "--model", "pinhole", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "the views do not determine the intrinsics: fx " in err and "(95%: " in err
    assert "No camera file written; pass --force" in err and not out.exists()
    assert main(["calibrate", str(CHARUCO), "--board", BOARD, "--model", "pinhole", "--out", str(out),
                 "--force"]) == 0
    cam = read_toml(out)
    assert cam.quality["intrinsics_determined"] is False
    lo, hi = cam.quality["intrinsics_95"]["fx"]
    assert lo < cam.fx < hi and (hi - lo) > 0.1 * cam.fx
    assert any("do not determine the intrinsics" in w for w in cam.quality["warnings"])


@needs_frobisher
def test_a_dslr_bracket_reaches_exposure_fit_through_import_and_beats_opencvs_debevec(tmp_path, capsys):
    from capture.camera import read_toml
    imported = tmp_path / "imported"
    assert main(["capture", "import", str(FROBISHER), "--out", str(imported)]) == 0
    assert "3 frame(s) from Canon EOS 5D Mark II, exposure 0.125, 1, 8 s, ISO 100, manual" in capsys.readouterr().out
    folder = imported / "set_01"
    out = tmp_path / "fitted.toml"
    assert main(["exposure", "fit", str(folder), "--camera", str(folder / "camera.toml"), "--out", str(out)]) == 0
    response = read_toml(out).imaging.response
    assert response.fit["exposure_us"] == [125000.0, 1000000.0, 8000000.0]
    from isu_validate.bench.real import response_rows
    rows = {r["tool"].split()[0]: r for r in response_rows([FROBISHER], with_defaults=False)}
    ours, cv = rows["isu-validate"], rows["OpenCV"]
    assert ours["neighbour_rms_codes"] < cv["neighbour_rms_codes"]          # 9.0 vs 12.9 codes
    assert cv["log_curve_rms_vs_ours"] < 0.15                               # the same curve within ~10%


@needs_frobisher
def test_the_passport_is_read_where_the_user_points_and_matches_colour_science(tmp_path, capsys):
    real = FROBISHER / "IMG_2601.jpg"
    out = tmp_path / "ccm.json"
    assert main(["exposure", "colour", "--real", str(real), "--sim", "reference", "--out", str(out)]) == 2
    assert "--chart-box" in capsys.readouterr().err          # ~1/15 of the frame: no detector finds it
    assert main(["exposure", "colour", "--real", str(real), "--sim", "reference", "--out", str(out),
                 "--chart-box", PASSPORT_BOX]) == 0
    report = json.loads(out.read_text())
    assert report["patches"]["used"] == 24 and report["de2000_before"]["mean"] > 15
    assert report["de2000_after"]["mean"] < 3
    from isu_validate.bench.real import colour_rows
    rows = colour_rows(real, PASSPORT_BOX)
    plain = next(r for r in rows if r["tool"].startswith("colour-science") and r["direction"] == "reference -> camera")
    assert rows[0]["after"]["mean"] <= plain["after"]["mean"] + 0.05
