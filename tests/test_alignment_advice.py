"""The alignment aid says which way to turn the camera: degrees from the registration and the focal length,
in words, on frames made by turning a known camera by known angles (K R^T K^-1 warps of one picture)."""
import math
import re

import cv2
import numpy as np
import pytest

from capture.alignment import Turn, align, camera_turn, text_scale, turn_words
from capture.camera import Camera

K = np.array([[300.0, 0, 319.5], [0, 300.0, 239.5], [0, 0, 1]])
CAMERA = Camera("test", "pinhole", 640, 480, [300.0, 300.0, 319.5, 239.5])


def rotation(pan=0.0, tilt=0.0, roll=0.0) -> np.ndarray:
    """The real camera's axes in the render camera's (OpenCV: x right, y down, z forward): turned ``pan``
    degrees right (about y), ``tilt`` up (about x) and ``roll`` clockwise seen from behind (about z)."""
    a, b, c = (math.radians(v) for v in (pan, tilt, roll))
    ry = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    rx = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return ry @ rx @ rz


def homography(R: np.ndarray) -> np.ndarray:
    """Render pixel -> pixel of the camera turned by R (same lens, same place)."""
    return K @ R.T @ np.linalg.inv(K)


def picture(seed=0, w=640, h=480) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = np.full((h, w, 3), 80, np.uint8)
    for _ in range(40):
        colour = tuple(int(v) for v in rng.integers(0, 255, 3))
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        kind = rng.integers(0, 3)
        if kind == 0:
            cv2.rectangle(img, (x, y), (x + int(rng.integers(20, 120)), y + int(rng.integers(20, 120))), colour, -1)
        elif kind == 1:
            cv2.circle(img, (x, y), int(rng.integers(10, 60)), colour, -1)
        else:
            cv2.line(img, (x, y), (int(rng.integers(0, w)), int(rng.integers(0, h))), colour, 3)
    return img


def shot(img: np.ndarray, R: np.ndarray, gain=0.8, noise=6.0) -> np.ndarray:
    """What the turned camera photographs: the picture warped, darker and noisy."""
    out = cv2.warpPerspective(img, homography(R), img.shape[1::-1], borderMode=cv2.BORDER_REPLICATE)
    out = out.astype(np.float32) * gain + np.random.default_rng(1).normal(0, noise, img.shape)
    return np.clip(out, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("pan,tilt,roll", [(2, 0, 0), (-3, 0, 0), (0, 1, 0), (0, -2, 0), (0, 0, 3), (4, -2, 1.5)])
def test_a_turned_camera_gives_back_the_turn_that_undoes_it(pan, tilt, roll):
    turn = camera_turn(homography(rotation(pan, tilt, roll)), 300.0, 300.0, 319.5, 239.5)
    # the camera turned right must turn left, tilted up must tilt down, rolled clockwise must roll back
    assert turn.pan_deg == pytest.approx(-pan, abs=0.1 + 0.05 * abs(tilt))
    assert turn.tilt_deg == pytest.approx(tilt, abs=0.1 + 0.05 * abs(pan))
    assert turn.roll_deg == pytest.approx(-roll, abs=0.1 + 0.05 * (abs(pan) + abs(tilt)))
    assert turn.scale == pytest.approx(1.0, abs=0.01)   # a turn alone changes no distance


def test_the_words_say_which_way_and_how_far():
    assert turn_words(Turn(-2.04, 1.0, 0.0, 1.0)) == "turn 2.0° left, tilt 1.0° down"
    assert turn_words(Turn(0.5, -3.26, -0.6, 1.0)) == ("turn 0.5° right, tilt 3.3° up, roll 0.6° anticlockwise "
                                                       "(seen from behind the camera)")
    assert turn_words(Turn(0.1, -0.2, 0.1, 1.08)) == "move back: things look 8% larger than in the render"
    assert turn_words(Turn(0.1, 0.0, 0.0, 1.01)) == "hold the camera: within 0.3°"


@pytest.mark.parametrize("pan,tilt,roll,words", [
    (2, 0, 0, "turn 2.0° left"),
    (0, 1, 0, "tilt 1.0° down"),
    (0, 0, -3, r"roll 3.0° clockwise \(seen from behind the camera\)"),
    (-4, 2, 1.5, r"turn 4\.0° right, tilt (1\.9|2\.0)° down, roll 1\.[56]° anticlockwise "
                 r"\(seen from behind the camera\)"),
])
def test_the_aid_reads_the_turn_off_a_photo(pan, tilt, roll, words):
    img = picture()
    result, _ = align(img, shot(img, rotation(pan, tilt, roll)), CAMERA)
    assert result.method == "ECC" and result.confident
    assert (result.pan_deg, result.tilt_deg, result.roll_deg) == pytest.approx((-pan, tilt, -roll), abs=0.15)
    assert re.fullmatch(words, result.advice), result.advice   # combined turns do not split exactly: 0.1°


def test_when_ecc_cannot_follow_features_find_the_turn():
    """A 12 degree turn and an 8 degree roll: beyond ECC's reach, SIFT and a homography get it."""
    img = picture()
    result, _ = align(img, shot(img, rotation(12, 0, 8)), CAMERA)
    assert result.method == "features" and result.confident and result.verdict == "off"
    assert (result.pan_deg, result.roll_deg) == pytest.approx((-12, -8), abs=0.3)
    assert result.advice.startswith("turn 11.9° left") or result.advice.startswith("turn 12.0° left")


def test_an_unsure_registration_still_shows_the_shift_and_says_so():
    """Half the frame shows something else (people moved, a door open): the registration is unsure, the
    shift and the advice are shown, marked low confidence, and the verdict is not "aligned"."""
    img, other = picture(), picture(seed=7)
    frame = shot(img, rotation(2, -1, 0))
    frame[:, 320:] = other[:, 320:]
    result, image = align(img, frame, CAMERA)
    assert not result.confident and result.score < 0.5
    assert result.shift_px is not None and "low confidence" in result.line()
    assert (result.pan_deg, result.tilt_deg) == pytest.approx((-2, -1), abs=0.4)
    assert result.verdict == "check"


def test_the_banner_grows_with_the_image():
    """A 640x480 frame gives a 1280-wide aid with text of about 20 px; twice the frame, twice the text."""
    assert text_scale(1280) == pytest.approx(0.9) and text_scale(2560) == pytest.approx(2 * text_scale(1280))
    img = picture()
    small, big = (align(cv2.resize(img, s), cv2.resize(shot(img, rotation(1, 0, 0)), s), CAMERA)[1]
                  for s in ((640, 480), (1280, 960)))
    banner = small.shape[0] - 480
    assert banner >= 60 and big.shape[0] - 960 >= 1.8 * banner
    row = small[:banner].max(axis=2)
    text_rows = np.flatnonzero((row > 120).any(axis=1))   # bright text on the dark box
    assert text_rows.size and text_rows.max() - text_rows.min() >= 40
