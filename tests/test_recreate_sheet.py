"""Recreation sheets a technician can set a car up from: each prints on one A4 page (headless Chromium,
as `make setup` installs it), and gives the camera's aim, what the light levels mean, the driver's
kilograms at the rendered height, the features the render hid, and pictures rendered for the sheet.
Runs come from the real search loop with test doubles; the sheets' renderer is a painter double
(one test renders with Blender)."""
import json
import math
import re
from dataclasses import replace

import cv2
import numpy as np
import pytest
from PIL import Image

from capture.camera import Camera, load_camera, look_at_rotation, write_toml
from isu_validate.pairs import PairsDir
from isu_validate.protocols import RenderResult
from isu_validate.recreate import plan_recreation, sheet_content
from isu_validate.recreate.aim import camera_aim
from isu_validate.recreate.guide import checklist
from isu_validate.recreate.light import light_rows
from isu_validate.recreate.pictures import Picture, Setup, projected_boxes
from isu_validate.recreate.sheet import SheetInfo, page, sheet_html
from isu_validate.render.cabin import load_cabin
from isu_validate.search import run_search
from isu_validate.space import load_space
from tests.test_report_browser import CHROMIUM, chromium
from tests.test_run import config

PHONE_IN_CABIN = ([0.0, 0.18, 0.98], [0.06, 0.26, 1.12])   # by the driver's right ear, in front of the camera


class Painter:
    """The sheets' renderer double: paints at the camera's size, labels the few visible pixels of the phone
    and knows where the whole phone is in the cabin (``bounds``)."""
    opened: list["Painter"] = []

    def __init__(self, preset, camera, cabin, space, min_visible):
        self.preset, self.camera, self.closed = preset, camera, False
        Painter.opened.append(self)

    def render(self, scene, out):
        w, h = self.camera.width, self.camera.height
        img = np.zeros((h, w, 3), np.uint8)
        img[...] = np.linspace(40, 200, w, dtype=np.uint8)[None, :, None]
        cv2.circle(img, (int(0.6 * w), int(0.3 * h)), int(0.1 * w), (90, 160, 220), -1)   # a head
        cv2.imwrite(str(out), img)
        label = out.with_name(out.stem + ".label.json")
        box = [0.6 * w, 0.25 * h, 0.62 * w, 0.3 * h]
        label.write_text(json.dumps({"visible": {"phone": {"pixels": 12, "bbox": box},
                                                 "driver_face": {"pixels": 900, "bbox": [0.5 * w, 0.2 * h,
                                                                                         0.7 * w, 0.4 * h]}}}))
        return RenderResult(out, {"label": label})

    def bounds(self, scene):
        return {"phone": PHONE_IN_CABIN}

    def close(self):
        self.closed = True


def printed_pages(html, tmp_path) -> int:
    """Pages of ``html`` printed to PDF by headless Chromium (A4 from the page's CSS, no header or footer)."""
    assert CHROMIUM, "chromium is missing: `make setup` installs it (scripts/setup_system.sh)"
    pdf = tmp_path / f"{html.parent.name}-{html.stem}.pdf"
    result = chromium(html, tmp_path / "profile-pdf", f"--print-to-pdf={pdf}", "--no-pdf-header-footer")
    assert result.returncode == 0 and pdf.is_file(), result.stderr[-2000:]
    return len(re.findall(rb"/Type\s*/Page\b(?!s)", pdf.read_bytes()))


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    small = write_toml(load_camera("default").scaled(0.5), root / "small.toml")   # the sheets render 640x480
    path = root / "run"
    cfg = config(path, budget_tests=24)
    cfg.pipeline = replace(cfg.pipeline, camera=str(small))
    run_search(cfg)
    return path


@pytest.fixture(scope="module")
def pairs(run_dir, tmp_path_factory):
    Painter.opened.clear()
    out = tmp_path_factory.mktemp("pairs") / "pairs"
    plan_recreation([run_dir], "mixed", 4, seed=0, out=out, open_renderer=Painter)
    return out


def test_each_sheet_prints_on_one_a4_page(pairs, tmp_path):
    """The overview, then one page per scene (it was 9 pages for 4 scenes: every sheet spilled over)."""
    assert printed_pages(pairs / "index.html", tmp_path) == 1 + 4
    assert printed_pages(pairs / "S01" / "sheet.html", tmp_path) == 1


def test_the_fullest_sheet_still_fits_one_page(tmp_path):
    """Every feature of the space active, the longest words, three hidden features and ten things to crop."""
    space, cabin = load_space(), load_cabin("default")
    scene = {"driver_gender": "FEMALE", "driver_emotion": "SERIOUS", "driver_height": "H4", "driver_weight": "W4",
             "phone_position": "P10", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "YES",
             "child": "YES", "child_seat_orientation": "REAR_FACING", "car_lights": "ON", "external_light": "LOW",
             "luggage": "YES", "luggage_position": "BACK", "luggage_colour": "ANTHRACITE",
             "luggage_orientation": 135.0, "phone_codriver_seat": "YES", "colacan_codriver_seat": "YES",
             "colabottle_codriver_seat": "YES"}
    parts = ("driver_face", "driver", "phone", "seat_belt", "child_seat", "child", "luggage",
             "phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat")
    sample = _sample(tmp_path / "pairs" / "S01", scene, occluded={"phone_position": 0.12, "child": 0.02,
                                                                   "luggage": 0.0})
    camera = load_camera("default")
    picture = _picture(sample, camera, {p: (100 + 40 * k, 100, 140 + 40 * k, 200) for k, p in enumerate(parts)})
    info = SheetInfo(7, 12, "a-very-long-run-name-for-testing test g0012-i009", True,
                     [f"change number {k} with a long description of what to do" for k in range(12)], 61.5)
    content = sheet_content(sample, space, cabin, info, picture, Setup(camera, "default", space, {}))
    assert len(content.items) == len(scene) and len(content.crops) == 7   # the hidden three and the smallest
    sample.sheet.write_text(page("S01", sheet_html(content, "sheet.png")))
    assert printed_pages(sample.sheet, tmp_path) == 1


def test_the_sheet_gives_the_cameras_aim_in_degrees(pairs):
    """A camera turned to pan 150°, tilt -20°, roll 5° (clockwise seen from behind) reads back as that; the
    sheet gives the run camera's place, mounting height, pan/tilt/roll and a marked view."""
    position = np.array([0.6, 0.1, 1.2])
    heading = np.array([math.cos(math.radians(20)) * math.cos(math.radians(150)),
                        math.cos(math.radians(20)) * math.sin(math.radians(150)), -math.sin(math.radians(20))])
    R = look_at_rotation(position, position + heading)
    turn = math.radians(5)   # camera x towards camera y: clockwise seen from behind
    R = R @ np.array([[math.cos(turn), -math.sin(turn), 0], [math.sin(turn), math.cos(turn), 0], [0, 0, 1]])
    aim = camera_aim(Camera("turned", "pinhole", 640, 480, [300.0, 300.0, 319.5, 239.5], position, R, True))
    assert (aim.pan_deg, aim.tilt_deg, aim.roll_deg) == pytest.approx((150.0, -20.0, 5.0), abs=1e-6)
    assert aim.height_m == pytest.approx(1.2) and aim.point == pytest.approx(tuple(position + heading))
    sheet = (pairs / "S01" / "sheet.html").read_text()
    # the run's camera: the default rig's pose (0.60, 0, 1.17) looking at (-0.55, 0.12, 0.60)
    assert "mounted 1.17 m above the floor" in sheet
    assert "faces the rear, turned 6.0° towards the car&#x27;s left (pan 174.0°)" in sheet
    assert "tilted 26.2° down (tilt -26.2°), picture level (roll +0.0°)" in sheet
    assert "What the camera should see" in sheet and re.search(r'<div class="frame"><img src="sheet.png"', sheet)
    assert "<line" in sheet.split('<div class="frame">')[1].split("</figure>")[0]   # the aim cross on it


def test_the_light_levels_say_what_was_rendered_and_what_to_arrange(pairs):
    """From the cabin rig: each value's sky strength and window light (and share of the brightest), the
    lamps, and the practical words the rig gives; the scene's value marked."""
    space, cabin = load_space(), load_cabin("default")
    cabin["recreate"]["external_light"]["practical"]["MEDIUM"] = "a rainy afternoon in the car park"
    cabin["lighting"]["window_light_w"]["MEDIUM"] = 12.0
    scene = {**space.sample(np.random.default_rng(0), 1)[0], "external_light": "MEDIUM", "car_lights": "ON"}
    rows = {(r.feature, r.value): r for r in light_rows(space, scene, cabin)}
    assert set(rows) == {("external_light", v) for v in ("LOW", "MEDIUM", "HIGH")} | {("car_lights", "ON"),
                                                                                     ("car_lights", "OFF")}
    medium = rows["external_light", "MEDIUM"]
    assert medium.chosen and not rows["external_light", "HIGH"].chosen and rows["car_lights", "ON"].chosen
    assert medium.practical == "a rainy afternoon in the car park"
    assert medium.rendered == "city sky x4.8, window light 12 W/m²" and medium.relative == "0.5 (-1.0 stops)"
    assert rows["car_lights", "ON"].rendered == "2 warm lamps of 14 W (roof, x = +0.15, -0.70 m)"
    sheet = (pairs / "S01" / "sheet.html").read_text()
    for value in ("LOW", "MEDIUM", "HIGH"):   # the shipped rig's words on every sheet
        assert _esc(load_cabin("default")["recreate"]["external_light"]["practical"][value]) in sheet
    assert sheet.count("◀ this scene") == 2


def test_the_drivers_weight_is_given_at_the_rendered_height():
    space, cabin = load_space(), load_cabin("default")
    base = space.sample(np.random.default_rng(1), 1)[0]
    for height, weight, words in (("H4", "W2", "BMI 21-25: 72-86 kg at 1.85 m (the rendered body 79 kg)"),
                                  ("H1", "W4", "BMI 30-35: 72-84 kg at 1.55 m (the rendered body 77 kg)")):
        items = {i.feature: i for i in checklist(space, {**base, "driver_height": height, "driver_weight": weight},
                                                 cabin)}
        assert words in items["driver_weight"].text and "1.55-1.85" not in items["driver_weight"].text


def test_a_feature_the_render_hid_is_flagged_and_cropped_where_it_is(tmp_path):
    """S01's phone at the ear, 12% visible: flagged (set it, it is not judged), its crop taken around the
    whole phone (projected from the cabin) and outlined; without that, a placeholder saying so."""
    space, cabin = load_space(), load_cabin("default")
    scene = {**space.sample(np.random.default_rng(2), 1)[0], "phone_position": "P1"}
    sample = _sample(tmp_path / "S01", scene, occluded={"phone_position": 0.12})
    camera = load_camera("default")
    picture = _picture(sample, camera, {"phone": (384.0, 120.0, 397.0, 144.0)},
                       projected_boxes({"phone": PHONE_IN_CABIN}, camera))
    content = sheet_content(sample, space, cabin, SheetInfo(1, 1, "run test t", True), picture,
                            Setup(camera, "default", space, {}))
    html = sheet_html(content, "sheet.png")
    assert "hidden from the camera in the render (12% visible): set it, it is not judged" in html
    [(items, crop)] = [(i, c) for i, c in content.crops if i[0].feature == "phone_position"]
    assert crop.outlined and crop.uri.startswith("data:image/jpeg;base64,")
    shown = _decode(crop.uri)
    assert min(shown.size) > 60 and np.asarray(shown).std() > 20     # a picture around it, not an empty patch
    blind = Picture(picture.image, camera, {}, {}, True)
    content = sheet_content(sample, space, cabin, SheetInfo(1, 1, "run test t", True), blind, None)
    [(items, crop)] = [(i, c) for i, c in content.crops if i[0].feature == "phone_position"]
    assert crop.uri is None and "nothing of it shows from the camera" in sheet_html(content, "sheet.png")


def test_the_sheets_pictures_are_rendered_at_the_sheets_size(pairs, run_dir):
    """The run rendered 320x240 (a small camera): each sheet's picture is the scene rendered again at the
    standard preset and 640x480; sim.png stays the run's frame (what the SUT saw)."""
    painter = Painter.opened[0]
    assert painter.preset == "standard" and (painter.camera.width, painter.camera.height) == (640, 480)
    assert painter.camera.fx == pytest.approx(300.0) and all(p.closed for p in Painter.opened)
    manifest = json.loads((pairs / "pairs.json").read_text())
    for sample in PairsDir(pairs).samples():
        assert Image.open(sample.sheet_image).size == (640, 480)
        run_frame = run_dir / "images" / f"{manifest['samples'][int(sample.name[1:]) - 1]['test_id']}.png"
        assert sample.sim.read_bytes() == run_frame.read_bytes()
        assert 'class="target"><img src="sheet.png"' in sample.sheet.read_text()
        assert "rendered for this sheet, 640x480" in sample.sheet.read_text()


@pytest.mark.blender
@pytest.mark.slow
def test_blender_renders_a_sheets_picture_at_640x480(run_dir, tmp_path):
    out = tmp_path / "pairs"
    plan = plan_recreation([run_dir], "failing", 1, seed=0, out=out)
    sample = PairsDir(out).sample(plan.samples[0]["sample"])
    assert Image.open(sample.sheet_image).size == (640, 480)
    label = json.loads((sample.path / "sheet.label.json").read_text())
    assert label["preset"] == "standard" and "driver" in label["visible"]


# ---------------------------------------------------------------------- helpers
def _sample(folder, scene, occluded):
    from isu_validate.pairs import Sample
    folder.mkdir(parents=True)
    space = load_space()
    (folder / "scene.json").write_text(json.dumps({"space": space.name, "scene": space.canonical(scene),
                                                   "occluded": list(occluded), "visibility": occluded}))
    return Sample(folder)


def _picture(sample, camera, visible, whole=None):
    """A painted sheet picture (a gradient and a head) with the given boxes of visible and whole parts."""
    img = np.zeros((camera.height, camera.width, 3), np.uint8)
    img[...] = np.linspace(30, 220, camera.width, dtype=np.uint8)[None, :, None]
    cv2.circle(img, (int(0.6 * camera.width), int(0.3 * camera.height)), int(0.1 * camera.width), (90, 160, 220), -1)
    cv2.imwrite(str(sample.sheet_image), img)
    return Picture(sample.sheet_image, camera, visible, dict(visible) if whole is None else whole, True)


def _decode(uri: str) -> Image.Image:
    import base64
    import io
    return Image.open(io.BytesIO(base64.b64decode(uri.split(",", 1)[1])))


def _esc(text: str) -> str:
    from isu_validate.analysis.html import esc
    return esc(text)
