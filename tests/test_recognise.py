"""`recognise`: the photo-trained yardsticks (real weights) on real photographs with pinned reads, and the
command on small frame folders and pairs: occluded faces counted apart, black, empty and corrupt frames."""
import json

import cv2
import numpy as np
import pytest
from skimage import data

from isu_validate.archive.output_dir import OutputInUse
from isu_validate.cli import main
from isu_validate.devices import resolve_torch_device
from isu_validate.errors import InputError
from isu_validate.recognition import photos
from isu_validate.recognition.expression import HAPPY, LABELS
from isu_validate.recognition.objects import square_crop, upright_crop
from isu_validate.recognition.read import Yardsticks
from isu_validate.recognition.tally import auc, wilson
from isu_validate.yardstick import measure
from isu_validate.yardstick.measure import RecogniseSettings, recognise

pytestmark = pytest.mark.usefixtures("few_torch_threads")

HEAD = [160, 20, 290, 200]     # the astronaut's head, as a render label's inclusive box would hold it
CAMERA_SIDECAR = {"device": "v4l2:/dev/video0", "exposure_us": 8000}
STAND_IN_SIDECAR = {"device": "stand-in render (not a camera)", "stand_in": True}


@pytest.fixture(scope="module")
def models():
    return Yardsticks.load("cpu")


@pytest.fixture()
def shared_models(models, monkeypatch):
    """The command loads the same real models the module already has (1.3 s a load)."""
    monkeypatch.setattr(measure.Yardsticks, "load", classmethod(lambda cls, device="cpu": models))
    return models


def label(emotion="HAPPY", visible=None, occluded=(), **scene) -> dict:
    return {"scene": {"driver_emotion": emotion, "external_light": "MEDIUM", "car_lights": "OFF", **scene},
            "preset": "draft", "visible": visible if visible is not None else {"driver_face": {"bbox": HEAD}},
            "occluded": list(occluded)}


def frame(folder, name, rgb, lab) -> None:
    folder.mkdir(exist_ok=True)
    cv2.imwrite(str(folder / f"{name}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    (folder / f"{name}.label.json").write_text(json.dumps(lab))


def run(sources, out, overwrite=False, **kw) -> dict:
    return recognise(RecogniseSettings(tuple(str(s) for s in sources), **kw), out, resolve_torch_device("cpu"),
                     overwrite=overwrite)


def row(summary, measure_name, kind="render", split="all", value="all") -> dict:
    return next(r for r in summary["rows"] if (r["measure"], r["kind"], r["split"], r["value"])
                == (measure_name, kind, split, value))


# ---- the yardsticks on real photographs: pinned known values

def test_mtcnn_finds_the_astronauts_face_and_no_face_on_a_cat(models):
    faces = models.faces.detect(data.astronaut())
    assert len(faces) == 1 and faces[0].p > 0.99
    assert faces[0].box == pytest.approx((181, 62, 268, 172), abs=3)
    assert models.faces.detect(data.chelsea()) == []


def test_fer_reads_the_astronauts_smile_happy_down_to_24_px(models):
    reads = photos.astronaut_face(models)
    assert [r["face_px"] for r in reads] == [110, 48, 24]
    assert all(r["found"] and r["read"] == "happy" and r["p_happy"] > 0.98 for r in reads)


def test_fer_in_torch_reads_a_fer_crop_as_keras_did(models):
    """Keras 3.15 (torch backend) gave P(happy) 1.000 on this crop; the torch module matched it to 5e-7."""
    grey = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2GRAY)
    p = models.expression.read(grey, [(170, 40, 110, 130)])[0]
    assert p.sum() == pytest.approx(1, abs=1e-5) and LABELS[p.argmax()] == "happy" and p[HAPPY] > 0.99


def test_lfw_faces_are_found_and_non_faces_are_not(models):
    result = photos.lfw(models, n=15)     # all 200 at 100 px: 98 of 100 faces, 0 of 100 non-faces
    assert result["faces"] >= 14 and result["non_faces"] == 0


def test_imagenet_reads_a_real_cup_as_espresso(models):
    reads = photos.cup(models)
    assert [r["top1"] for r in reads] == ["espresso"] * 3
    assert all(r["cup_in_top5"] for r in reads[:2])


def _cup_on_its_side():
    """scikit-image's coffee photograph turned a quarter clockwise: the cup's top now points right."""
    x0, y0, x1, y1 = photos.CUP_BOX
    height = data.coffee().shape[0]
    return np.ascontiguousarray(np.rot90(data.coffee(), -1)), (height - y1, x0, height - y0, x1)


def test_a_real_cup_on_its_side_reads_surely_again_once_turned_upright(models):
    side, box = _cup_on_its_side()
    as_seen, upright = models.objects.top([square_crop(side, box), upright_crop(side, box, (1.0, 0.0))])
    assert upright[0][0] == "espresso" and upright[0][1] > 0.8     # as the photograph stands (0.94)
    assert as_seen[0][1] < 0.5                                       # lying: 0.35, "coffee mug" close behind


def test_upright_crop_turns_the_things_top_up_and_keeps_an_upright_one_as_it_is():
    bar = np.zeros((100, 100, 3), np.uint8)
    bar[45:55, 30:70] = 100
    bar[45:55, 62:70] = 255                                  # the bar's top: its bright right end
    as_seen = square_crop(bar, (30, 45, 70, 55))
    for up, top_row in (((1.0, 0.0), True), ((0.8, 0.6), True), ((-1.0, 0.0), False), ((-0.7, -0.6), False)):
        crop = upright_crop(bar, (30, 45, 70, 55), up)
        ys, xs = np.nonzero(crop[..., 0] == 255)
        assert crop.shape == (50, 50, 3) and abs(xs.mean() - 24.5) < 1.5      # on the crop's middle line
        assert (ys.mean() < 15) == top_row and (ys.mean() > 35) != top_row
        assert sorted(crop.ravel().tolist()) == sorted(as_seen.ravel().tolist())   # its pixels, turned
    for up in ((0.0, -1.0), (0.6, -0.8), (-0.6, -0.8)):      # within 45 degrees of upright: as it is
        assert np.array_equal(upright_crop(bar, (30, 45, 70, 55), up), as_seen)


def test_wilson_interval_and_auc_known_values():
    assert wilson(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    assert wilson(49, 60) == pytest.approx((0.7008, 0.8944), abs=1e-4)   # by hand from the formula
    assert wilson(0, 0) is None
    assert auc([0.9, 0.5], [0.1, 0.5]) == 0.875 and auc([], [0.1]) is None


# ---- the command on frame folders

def test_a_face_found_and_read_and_its_size(tmp_path, shared_models):
    frame(tmp_path / "frames", "astronaut", data.astronaut(), label())
    summary = run([tmp_path / "frames"], tmp_path / "out")
    assert row(summary, "face found")["hits"] == 1 and row(summary, "HAPPY read happy")["hits"] == 1
    assert row(summary, "face found", split="external_light", value="MEDIUM")["n"] == 1
    record = json.loads((tmp_path / "out" / "frames.jsonl").read_text())
    face = record["items"][0]
    assert face["found"] and 80 < face["width_px"] < 100 and face["expression"]["read"] == "happy"
    assert summary["frames"] == {"total": 1, "render": 1, "real": 0, "stand-in": 0, "stand_in_frames": 0,
                                 "real_frames": 0}
    assert {"sheets", "timing", "device", "models", "plausible_classes"} <= set(summary)
    assert (tmp_path / "out" / "sheet-render.png").is_file()


def test_a_fully_occluded_face_is_counted_apart_not_missed(tmp_path, shared_models):
    black = np.zeros((120, 160, 3), np.uint8)
    frame(tmp_path / "frames", "no-pixel", black, label(visible={}))          # not one pixel of the head
    frame(tmp_path / "frames", "too-little", black, label(occluded=["driver_emotion"]))
    summary = run([tmp_path / "frames"], tmp_path / "out")
    for name in ("face found", "HAPPY read happy"):
        r = row(summary, name)
        assert (r["n"], r["hits"], r["occluded"], r["rate"], r["ci95"]) == (0, 0, 2, None, None)


def test_a_black_frame_is_read_and_its_visible_face_is_a_miss(tmp_path, shared_models):
    frame(tmp_path / "frames", "black", np.zeros((240, 320, 3), np.uint8), label())
    summary = run([tmp_path / "frames"], tmp_path / "out")
    r = row(summary, "face found")
    assert (r["n"], r["hits"], r["occluded"]) == (1, 0, 0)
    assert r["ci95"] == pytest.approx([0.0, 0.7935], abs=1e-4)


@pytest.mark.parametrize("content", [b"", b"\x89PNG\r\n\x1a\n truncated"], ids=["empty", "corrupt"])
def test_an_empty_or_corrupt_image_is_a_clear_error(tmp_path, shared_models, capsys, content):
    frames = tmp_path / "frames"
    frame(frames, "good", data.astronaut(), label())
    (frames / "bad.png").write_bytes(content)
    (frames / "bad.label.json").write_text(json.dumps(label()))
    assert main(["recognise", str(frames), "--out", str(tmp_path / "out"), "--device", "cpu"]) == 2
    err = capsys.readouterr().err
    assert f"cannot decode frame {frames / 'bad.png'}" in err and "re-render or re-capture it" in err


def test_a_frame_without_its_label_and_a_missing_source_are_user_errors(tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    cv2.imwrite(str(frames / "x.png"), np.zeros((20, 20, 3), np.uint8))
    with pytest.raises(InputError, match="x.png needs x.label.json"):
        run([frames], tmp_path / "out")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        run([tmp_path / "nowhere"], tmp_path / "out")


def test_out_holding_something_else_is_refused_and_its_own_output_is_redone(tmp_path, shared_models):
    frame(tmp_path / "frames", "astronaut", data.astronaut(), label())
    other = tmp_path / "other"
    other.mkdir()
    (other / "run.json").write_text('{"identity": {}}')                 # a run, say
    with pytest.raises(OutputInUse, match="holds the output of `isu-validate run`"):
        run([tmp_path / "frames"], other)
    assert [p.name for p in other.iterdir()] == ["run.json"]
    run([tmp_path / "frames"], tmp_path / "out")
    run([tmp_path / "frames"], tmp_path / "out")                     # the same settings: done again
    with pytest.raises(OutputInUse, match="other settings"):
        run([tmp_path / "frames"], tmp_path / "out", limit=1)        # other settings: refused
    run([tmp_path / "frames"], tmp_path / "out", limit=1, overwrite=True)   # unless the user says so


def test_pairs_real_frames_beside_the_renders_and_stand_ins_marked(tmp_path, shared_models):
    sample = tmp_path / "pairs" / "S01"
    (sample / "real").mkdir(parents=True)
    lab = label(phone_position="P1", visible={"driver_face": {"bbox": HEAD}, "phone": {"bbox": [0, 300, 60, 360]}})
    (sample / "scene.json").write_text(json.dumps({"test_id": "S01", "scene": lab["scene"]}))
    (sample / "sim.label.json").write_text(json.dumps(lab))
    cv2.imwrite(str(sample / "sim.png"), cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR))
    for k, sidecar in enumerate((CAMERA_SIDECAR, STAND_IN_SIDECAR)):
        cv2.imwrite(str(sample / "real" / f"frame_{k:04d}.png"), cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR))
        (sample / "real" / f"frame_{k:04d}.json").write_text(json.dumps(sidecar))
    summary = run([tmp_path / "pairs"], tmp_path / "out")
    assert summary["frames"]["real_frames"] == 1 and summary["frames"]["stand_in_frames"] == 1
    assert {k: row(summary, "face found", kind=k)["hits"] for k in ("render", "real", "stand-in")} == \
        {"render": 1, "real": 1, "stand-in": 1}
    assert row(summary, "phone top-5", kind="real")["n"] == 1       # read on the aligned sim frame's box
    html = (tmp_path / "out" / "index.html").read_text()
    assert "STAND-IN FRAMES: 1 of 2" in html and "<th>render</th><th>real</th><th>stand-in</th>" in html


def test_a_thing_is_read_upright_where_its_label_says_where_its_top_points(tmp_path, shared_models):
    side, (x0, y0, x1, y1) = _cup_on_its_side()
    things = {"driver_face": {"bbox": HEAD}, "colabottle_codriver_seat": {"bbox": [x0, y0, x1 - 1, y1 - 1]}}
    frame(tmp_path / "frames", "told", side, {**label(visible=things, colabottle_codriver_seat="YES"),
                                              "up": {"colabottle_codriver_seat": [1.0, 0.0]}})
    frame(tmp_path / "frames", "untold", side, label(visible=things, colabottle_codriver_seat="YES"))
    summary = run([tmp_path / "frames"], tmp_path / "out")
    records = {r["name"]: r for r in map(json.loads, (tmp_path / "out" / "frames.jsonl").read_text().splitlines())}
    told, untold = (next(i for i in records[n]["items"] if i["feature"] == "bottle") for n in ("told", "untold"))
    assert told["up"] == [1.0, 0.0] and told["upright"]["top"][0][0] == "espresso"   # a cup, not a bottle
    assert "up" not in untold and "upright" not in untold    # a label from before `up`: read as seen only
    assert row(summary, "bottle top-5")["n"] == 2 and row(summary, "bottle top-5 upright")["n"] == 1
    assert summary["objects"]["render"]["bottle"]["upright"]["n"] == 1


def test_the_report_escapes_what_it_shows(tmp_path, shared_models):
    frame(tmp_path / "frames", "astronaut", data.astronaut(), label(emotion="<b>HAPPY</b>"))
    run([tmp_path / "frames"], tmp_path / "out")
    html = (tmp_path / "out" / "index.html").read_text()
    assert "<b>HAPPY</b>" not in html and "&lt;b&gt;HAPPY&lt;/b&gt;" in html


@pytest.mark.parametrize("up", [[0.0, 0.0], "up", [1.0], {"x": 1}])
def test_a_malformed_up_in_a_label_names_the_frame(tmp_path, up):
    frame(tmp_path / "frames", "bad", np.zeros((60, 80, 3), np.uint8), {**label(), "up": {"phone": up}})
    with pytest.raises(InputError, match=r"label of .*bad\.png has a malformed 'up'"):
        run([tmp_path / "frames"], tmp_path / "out")
    assert not (tmp_path / "out" / "frames.jsonl").exists()


def test_a_real_frame_of_another_aspect_gets_the_sims_boxes_and_tops_stretched_with_it():
    from pathlib import Path

    from isu_validate.recognition.frames import Frame
    sim = Frame(Path("x.png"), "x", "real", None, {}, {"phone": (10, 20, 30, 40)}, boxes_size=(100, 100),
                up={"phone": (0.6, -0.8)})
    assert sim.boxes_for(200, 100) == {"phone": (20, 20, 60, 40)}
    assert sim.up_for(200, 100)["phone"] == pytest.approx((1.2 / np.hypot(1.2, 0.8), -0.8 / np.hypot(1.2, 0.8)))
    assert sim.up_for(100, 100) == {"phone": (0.6, -0.8)}
