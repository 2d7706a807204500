"""``reference train --windows ... --detector yolov4-tiny|FILE.cfg|FILE.onnx``: window heads stacked with a
photo-trained detector's score.

The detectors here are real networks built in the test (stand-ins for a COCO detector, never shipped): an ONNX graph
run by onnxruntime and a darknet network (cfg, weights, names) run by OpenCV's DNN module. Each scores "cell phone"
where the frame is much bluer than red, as the painted phone's lit screen is, and nowhere else. The built-in
YOLOv4-tiny that `make setup` installs is opened for real too."""
import json
import shutil
import struct

import numpy as np
import pytest

from isu_validate.errors import InputError
from isu_validate.reference.backbone import read_rgb
from isu_validate.reference.detector import (DETECTOR_FILE, DarknetYolo, FrameDetector, OnnxYolo, digest_of, logit,
                                            open_detector, open_in_model, parse_classes, views)
from isu_validate.reference.model import ReferenceISU
from isu_validate.reference.stacking import FOLDS, Folds, Stacking, folds
from isu_validate.space import load_space
from tests.test_reference import train_painted
from tests.test_reference_windows import SMALL, PhonePainter, belted_training_frames

SPACE = load_space()
SIDE = 64          # the stand-in's input square
CELL = 8           # it pools the frame in 8x8-pixel cells: 64 anchors


def onnx_detector(path, names=("person", "cell phone"), rows=None, metadata=True):
    """A YOLO-layout ONNX detector: output [1, 4 + classes, 64]; 'cell phone' = sigmoid(20 (blue - red) - 4) of
    each cell, every other row 0. ``rows`` overrides the output's row count (a wrong layout)."""
    import onnx
    from onnx import TensorProto, helper

    k = len(names)
    nodes = [
        helper.make_node("AveragePool", ["images"], ["pooled"], kernel_shape=[CELL, CELL], strides=[CELL, CELL]),
        helper.make_node("Split", ["pooled", "split"], ["r", "g", "b"], axis=1),
        helper.make_node("Sub", ["b", "r"], ["blue"]),
        helper.make_node("Mul", ["blue", "gain"], ["scaled"]),
        helper.make_node("Add", ["scaled", "offset"], ["z"]),
        helper.make_node("Sigmoid", ["z"], ["p"]),
        helper.make_node("Reshape", ["p", "row_shape"], ["phone"]),
        helper.make_node("Mul", ["phone", "zero"], ["nothing"]),
        helper.make_node("Concat", ["nothing"] * (4 + k - 1) + ["phone"] if rows is None else
                         ["nothing"] * (rows - 1) + ["phone"], ["output0"], axis=1),
    ]
    anchors = (SIDE // CELL) ** 2
    init = [helper.make_tensor("split", TensorProto.INT64, [3], [1, 1, 1]),
            helper.make_tensor("gain", TensorProto.FLOAT, [], [20.0]),
            helper.make_tensor("offset", TensorProto.FLOAT, [], [-4.0]),
            helper.make_tensor("zero", TensorProto.FLOAT, [], [0.0]),
            helper.make_tensor("row_shape", TensorProto.INT64, [3], [1, 1, anchors])]
    graph = helper.make_graph(nodes, "stand-in detector",
                              [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, SIDE, SIDE])],
                              [helper.make_tensor_value_info("output0", TensorProto.FLOAT,
                                                             [1, (4 + k) if rows is None else rows, anchors])],
                              init)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 9
    if metadata:
        for key, value in {"names": repr(dict(enumerate(names))), "imgsz": f"[{SIDE}, {SIDE}]",
                           "license": "test stand-in, no licence"}.items():
            model.metadata_props.add(key=key, value=value)
    onnx.save(model, str(path))
    return path


@pytest.fixture(scope="module")
def detector_file(tmp_path_factory):
    return onnx_detector(tmp_path_factory.mktemp("detector") / "standin.onnx")


@pytest.fixture(scope="module")
def stacked(tmp_path_factory, detector_file):
    detector = FrameDetector.open(detector_file, {"phone_position": "cell phone"})
    return train_painted(tmp_path_factory, "stacked", PhonePainter(), 30, 16, windows=SMALL, detector=detector)


def test_the_detector_reads_its_names_size_and_licence_and_scores_the_phone_where_it_is(detector_file, stacked):
    detector = OnnxYolo(detector_file)
    assert detector.names == ["person", "cell phone"] and detector.size == SIDE
    assert detector.licence == "test stand-in, no licence" and len(detector.sha256) == 64
    folder, _ = stacked
    images = sorted((folder / "work" / "held-out").glob("*.png"))
    scenes = [json.loads(p.with_suffix(".json").read_text())["scene"] for p in images]
    scores = [detector.best_scores(read_rgb(p), ["cell phone"])["cell phone"] for p in images]
    phone = [s for s, scene in zip(scores, scenes) if scene["phone_position"] != "NONE"]
    none = [s for s, scene in zip(scores, scenes) if scene["phone_position"] == "NONE"]
    assert phone and none and min(phone) > max(none)     # the stand-in sees the lit screen, not the grey decoy
    # a frame of any shape is letterboxed on grey into the square, its aspect kept
    boxed = detector.letterbox(np.zeros((30, 120, 3), np.uint8))
    assert boxed.shape == (1, 3, SIDE, SIDE) and boxed[0, 0, 0, 0] == pytest.approx(114 / 255)
    assert boxed[0, 0, SIDE // 2, 0] == 0.0


def test_window_heads_stacked_with_the_detector_answer_as_the_card_says(stacked, detector_file):
    folder, card = stacked
    model = folder / "model"
    meta = json.loads((model / "heads.json").read_text())
    stacking = meta["windows"]["calibration"]["phone_position"]
    assert set(stacking) == {"window", "detector", "intercept"} and stacking["detector"] > 0
    about = meta["windows"]["detector"]
    assert about == card["windows"]["detector"] and about["classes"] == {"phone_position": "cell phone"}
    assert (model / DETECTOR_FILE).read_bytes() == detector_file.read_bytes()   # the model folder carries it
    assert card["held_out"]["per_feature"]["phone_position"]["accuracy"] >= 0.9
    text = (model / "MODEL_CARD.md").read_text()
    assert "- Detector: the window heads it has a class for are stacked with an object detector" in text
    # renders from one viewpoint: the stacking's folds are by frame, and both records say so
    assert meta["windows"]["calibration_folds"] == card["windows"]["calibration_folds"] == f"{FOLDS} by frame"
    assert f"log-odds out of fold (folds {FOLDS} by frame)" in text
    assert "its licence: test stand-in, no licence" in text
    assert f"--detector {detector_file} --detector-tiles 2 --detector-class phone_position='cell phone'" in text
    assert about["tiles"] == 2 and "over the frame and its 2x2 tiles" in text
    # the SUT reads the frame through both and agrees with the card's held-out figure
    reader = ReferenceISU(SPACE, model)
    images = sorted((folder / "work" / "held-out").glob("*.png"))
    truth = [json.loads(p.with_suffix(".json").read_text())["scene"]["phone_position"] != "NONE" for p in images]
    said = [reader.read(p)[1]["phone_position"]["YES"] for p in images]
    assert np.mean([(p >= 0.5) == t for p, t in zip(said, truth)]) == pytest.approx(
        card["held_out"]["per_feature"]["phone_position"]["accuracy"])
    # and each answer is the stacking of the best window's log-odds and the detector's
    rgb = read_rgb(images[0])
    window = reader.calibration["phone_position"]
    seen = reader.detector.log_odds(rgb, ["phone_position"])["phone_position"]
    onnx = OnnxYolo(detector_file)
    assert seen == pytest.approx(logit(max(onnx.best_scores(v, ["cell phone"])["cell phone"] for v in views(rgb, 2))))
    assert isinstance(window, Stacking) and window.detector == pytest.approx(stacking["detector"])


def test_a_model_whose_detector_is_missing_or_another_is_refused(stacked, tmp_path, detector_file):
    folder, _ = stacked
    copy = tmp_path / "model"
    shutil.copytree(folder / "model", copy)
    (copy / DETECTOR_FILE).unlink()
    with pytest.raises(InputError, match="copy the model folder whole"):
        ReferenceISU(SPACE, copy)
    onnx_detector(copy / DETECTOR_FILE, names=("person", "cell phone", "cup"))   # another detector, same name
    with pytest.raises(InputError, match="is not the detector the model .* was fitted with"):
        ReferenceISU(SPACE, copy)


def test_bad_detector_files_are_refused_with_what_is_wrong(tmp_path):
    with pytest.raises(InputError, match="no such file; name yolov4-tiny"):
        open_detector(tmp_path / "absent.onnx")
    (tmp_path / "model.pt").write_bytes(b"torch")
    with pytest.raises(InputError, match="not a detector file this reads"):
        open_detector(tmp_path / "model.pt")
    (tmp_path / "garbage.onnx").write_bytes(b"not a graph")
    with pytest.raises(InputError, match="not a readable ONNX model"):
        open_detector(tmp_path / "garbage.onnx")
    with pytest.raises(InputError, match="no class names"):
        OnnxYolo(onnx_detector(tmp_path / "bare.onnx", metadata=False))
    with pytest.raises(InputError, match=r"not \[1, 4 \+ 2 classes, anchors\]"):
        OnnxYolo(onnx_detector(tmp_path / "rows.onnx", rows=5))
    # a graph whose rows show only when it runs (a dynamic export): its real session, answering 5 rows
    named = OnnxYolo(onnx_detector(tmp_path / "named.onnx"))
    real = named.session

    class FiveRows:
        get_inputs = real.get_inputs

        def run(self, outputs, feeds):
            return [np.zeros((1, 5, real.run(outputs, feeds)[0].shape[2]), np.float32)]
    named.session = FiveRows()
    with pytest.raises(InputError, match="it gave 5 rows per anchor, not 4 \\+ 2 classes"):
        named.best_scores(np.zeros((48, 64, 3), np.uint8), ["cell phone"])
    with pytest.raises(InputError, match="it has no class 'mobile'; its classes: person, cell phone"):
        FrameDetector.open(onnx_detector(tmp_path / "ok.onnx"), {"phone_position": "mobile"})


def test_detector_classes_default_for_the_phone_and_are_named_for_the_rest():
    assert parse_classes(None, ("phone_position",)) == {"phone_position": "cell phone"}
    assert parse_classes(["seat_belt=tie", "phone_position = mobile phone"], ("phone_position", "seat_belt")) == {
        "phone_position": "mobile phone", "seat_belt": "tie"}
    # COCO has no seat belt: a window feature without a class is calibrated alone, but a detector that stacks
    # nothing is a slip
    assert parse_classes(None, ("phone_position", "seat_belt")) == {"phone_position": "cell phone"}
    with pytest.raises(InputError, match="no window feature has a detector class \\(seat_belt\\); name one with "
                                         "--detector-class seat_belt=CLASS"):
        parse_classes(None, ("seat_belt",))
    with pytest.raises(InputError, match="write FEATURE=CLASS"):
        parse_classes(["seat_belt"], ("seat_belt",))
    with pytest.raises(InputError, match="'driver_gender' has no window head"):
        parse_classes(["driver_gender=person"], ("phone_position",))


def test_a_window_feature_without_a_detector_class_is_calibrated_alone_beside_a_stacked_one(stacked, detector_file):
    from isu_validate.reference.backbone import Backbone
    from isu_validate.reference.windows import WindowSettings, fit_window_heads
    images, scenes, labels = belted_training_frames(stacked[0])
    detector = FrameDetector.open(detector_file, {"phone_position": "cell phone"})
    assert detector.log_odds(read_rgb(images[0]), ["seat_belt"]) == {}     # nothing to read for the belt
    backbone = Backbone(160, 120, threads=2)
    both = WindowSettings(("seat_belt", "phone_position"), SMALL.height)
    heads, stackings, _, read = fit_window_heads(SPACE, both, backbone, images, scenes, labels, 3, detector)
    assert [h.feature for h in heads] == ["seat_belt", "phone_position"]
    assert stackings["seat_belt"].detector == 0.0 and isinstance(stackings["seat_belt"].describe(), list)
    assert stackings["phone_position"].detector > 0
    # the phone's stacking is the one fitted without the belt beside it
    alone = fit_window_heads(SPACE, SMALL, backbone, images, scenes, labels, 3, detector)[1]["phone_position"]
    assert stackings["phone_position"].window == pytest.approx(alone.window, rel=1e-6)
    assert stackings["phone_position"].detector == pytest.approx(alone.detector, rel=1e-6)
    assert all(set(frame) == {"seat_belt", "phone_position"} for frame in read)


def test_logits_of_sure_scores_stay_finite_and_folds_are_balanced_and_seeded():
    assert np.isfinite(logit(0.0)) and np.isfinite(logit(1.0)) and logit(0.5) == 0.0
    a = folds(23, seed=4)
    assert np.array_equal(a, folds(23, seed=4)) and not np.array_equal(a, folds(23, seed=5))
    assert sorted(np.bincount(a, minlength=FOLDS)) == [4, 4, 5, 5, 5]


def test_the_stacking_folds_are_the_viewpoints_when_the_renders_have_several():
    by_view = Folds.plan(["side", "door", "side", "mirror", "door"], seed=4)
    assert by_view.viewpoints == ("door", "mirror", "side") and len(by_view) == 3
    assert by_view.of.tolist() == [2, 0, 2, 1, 0] and by_view.describe() == "by viewpoint: door, mirror, side"
    # one viewpoint, or a frame that names none (a label without its camera): FOLDS by frame, as before
    for viewpoints in (["side"] * 23, ["side"] * 22 + [None]):
        plan = Folds.plan(viewpoints, seed=4)
        assert plan.viewpoints == () and len(plan) == FOLDS and np.array_equal(plan.of, folds(23, seed=4))
        assert plan.describe() == f"{FOLDS} by frame"


def test_a_stacking_fitted_on_two_viewpoints_leaves_each_out_in_turn(stacked, detector_file):
    from isu_validate.reference.backbone import Backbone
    from isu_validate.reference.windows import fit_window_heads
    images, scenes, labels = belted_training_frames(stacked[0])
    for i, label in enumerate(labels):
        label["camera"] = {"name": ("side", "door")[i % 2]}
    detector = FrameDetector.open(detector_file, {"phone_position": "cell phone"})
    backbone = Backbone(160, 120, threads=2)
    by_view = fit_window_heads(SPACE, SMALL, backbone, images, scenes, labels, 3, detector)
    by_frame = fit_window_heads(SPACE, SMALL, backbone, images, scenes, labels, 3, detector,
                                Folds(folds(len(images), 3)))
    # the labels' viewpoints decide the folds: the heads are the same either way, only the stacking moves
    assert by_view[1]["phone_position"] != by_frame[1]["phone_position"]
    assert np.allclose(by_view[0][0].weight, by_frame[0][0].weight, atol=1e-8)


def test_a_window_head_calibrated_alone_is_calibrated_out_of_fold(stacked):
    from isu_validate.reference.backbone import Backbone
    from isu_validate.reference.windows import WindowSettings, fit_window_heads
    images, scenes, labels = belted_training_frames(stacked[0])
    belt = WindowSettings(("seat_belt",), SMALL.height)
    backbone = Backbone(160, 120, threads=2)
    one = fit_window_heads(SPACE, belt, backbone, images, scenes, labels, 3)
    other = fit_window_heads(SPACE, belt, backbone, images, scenes, labels, 3, fold_plan=Folds(folds(len(images), 4)))
    # the same head, calibrated on other folds: a calibration in sample would not move with them
    assert np.allclose(one[0][0].weight, other[0][0].weight, atol=1e-8)
    assert one[1]["seat_belt"].detector == other[1]["seat_belt"].detector == 0.0
    assert one[1]["seat_belt"] != other[1]["seat_belt"]


def test_a_stored_calibration_reads_as_a_stacking_either_way():
    assert Stacking.from_meta([1.04, -3.05]) == Stacking(1.04, 0.0, -3.05)     # a window head alone
    stacked = Stacking(0.5, 0.4, -1.0)
    assert Stacking.from_meta(json.loads(json.dumps(stacked.describe()))) == stacked
    assert Stacking(1.04, 0.0, -3.05).describe() == [1.04, -3.05]              # stored as before: same fingerprint
    assert stacked.probability(2.0, 1.0) == pytest.approx(1 / (1 + np.exp(-(1.0 + 0.4 - 1.0))))


@pytest.mark.parametrize("argv, message", [
    (["--detector", "x.onnx"], "--detector stacks with window heads: give --windows"),
    (["--detector-class", "phone_position=cell phone"], "--detector-class and --detector-tiles say how a --detector"),
    (["--detector-tiles", "1"], "give --detector too"),
    (["--windows", "phone_position", "--detector", "absent.onnx"], "no such file"),
])
def test_the_command_refuses_a_detector_it_cannot_use_before_rendering(argv, message, tmp_path, capsys):
    from isu_validate.cli import main
    code = main(["reference", "train", "--n", "10", "--held-out", "2", "--workdir", str(tmp_path / "w"), *argv])
    assert code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "w" / "model").exists()     # nothing rendered, no folder claimed


def test_a_bench_recipe_names_its_detector_by_content_and_refuses_one_it_cannot_use(tmp_path, detector_file):
    from argparse import Namespace

    from isu_validate.bench.transfer import _train, parse_recipe, recipe_settings
    args = Namespace(preset="draft", n=4, held_out=2, seed=0, render_device="cpu", device="cpu")
    recipe = parse_recipe(f"side=train:n=4,windows=phone_position,detector={detector_file}")
    assert recipe.options["detector"] == str(detector_file)
    made = json.loads(recipe_settings(recipe, args)[1])
    assert made["detector_sha256"] == OnnxYolo(detector_file).sha256 and made["detector_tiles"] == 2
    tiles = parse_recipe(f"side=train:n=4,windows=phone_position,detector={detector_file},detector_tiles=1")
    assert json.loads(recipe_settings(tiles, args)[1])["detector_tiles"] == 1
    assert "detector_sha256" not in json.loads(recipe_settings(parse_recipe("side=train:n=4"), args)[1])
    with pytest.raises(InputError, match="detector_tiles= says how a detector= reads; add detector=yolov4-tiny"):
        _train(parse_recipe("side=train:n=4,windows=phone_position,detector_tiles=1"), tmp_path / "c", args)
    with pytest.raises(InputError, match="detector= stacks with window heads; add windows=FEATURE"):
        _train(parse_recipe(f"side=train:n=4,detector={detector_file}"), tmp_path / "a", args)
    with pytest.raises(InputError, match="no such file"):
        _train(parse_recipe(f"side=train:n=4,windows=phone_position,detector={tmp_path / 'x.onnx'}"),
               tmp_path / "b", args)
    assert not any((tmp_path / n / "cache").exists() for n in "abc")   # nothing rendered


# ---------------------------------------------------------------------------------------------- darknet detectors
def darknet_detector(folder, names=("person", "cell phone"), side=32, thresh=None, names_file=None):
    """A darknet YOLO of one 1x1 convolution and a [yolo] layer: objectness sigmoid(8 (blue - red) - 4) per cell and
    anchor, 'cell phone' probability sigmoid(4), every other class sigmoid(-4)."""
    folder.mkdir(parents=True, exist_ok=True)
    k = len(names)
    per, filters = 5 + k, 3 * (5 + k)
    (folder / "standin.cfg").write_text(
        f"[net]\nwidth={side}\nheight={side}\nchannels=3\n\n[convolutional]\nbatch_normalize=0\nfilters={filters}\n"
        "size=1\nstride=1\npad=0\nactivation=linear\n\n[yolo]\nmask=0,1,2\nanchors=10,14, 23,27, 37,58\n"
        f"classes={k}\nnum=3\n" + (f"thresh={thresh}\n" if thresh is not None else ""))
    bias, weight = np.zeros(filters, np.float32), np.zeros((filters, 3), np.float32)
    for anchor in range(3):
        o = anchor * per
        weight[o + 4], bias[o + 4] = [-8.0, 0.0, 8.0], -4.0          # RGB in: blue minus red
        bias[o + 5:o + 5 + k] = -4.0
        bias[o + 5 + names.index("cell phone")] = 4.0
    with open(folder / "standin.weights", "wb") as f:    # darknet's header: version 0.2.0, images seen (uint64)
        f.write(struct.pack("<iiiQ", 0, 2, 0, 0) + bias.tobytes() + weight.tobytes())
    (folder / (names_file or "standin.names")).write_text("\n".join(names) + "\n")
    return folder / "standin.cfg"


def painted(size, colour=(0, 0, 255)):
    """A black 640x480 RGB frame with a square of ``colour`` ``size`` px wide at (500, 300)."""
    frame = np.zeros((480, 640, 3), np.uint8)
    frame[300:300 + size, 500:500 + size] = colour
    return frame


def test_a_darknet_detector_reads_its_three_files_and_keeps_low_scores_to_rank_frames(tmp_path):
    cfg = darknet_detector(tmp_path / "a", thresh=0.25)
    detector = open_detector(cfg)
    assert isinstance(detector, DarknetYolo) and detector.names == ["person", "cell phone"] and detector.size == 32
    assert detector.licence == "not stated in the files" and len(detector.sha256) == 64
    blue, red, purple = (np.full((480, 640, 3), c, np.uint8) for c in ((0, 0, 255), (255, 0, 0), (128, 0, 128)))
    high = detector.best_scores(blue, ["cell phone"])["cell phone"]
    low = detector.best_scores(red, ["cell phone"])["cell phone"]
    assert high == pytest.approx(1 / (1 + np.exp(-4)) / (1 + np.exp(-4)), rel=1e-3)   # objectness x class
    # OpenCV zeroes the class scores of boxes under the layer's threshold (the cfg's 0.25 here); read with it at 0,
    # a frame with no phone still has a score below the others, so frames rank
    assert 0 < low < 1e-4 and low < detector.best_scores(purple, ["cell phone"])["cell phone"] < 0.02
    # a YOLOv2 [region] layer's threshold goes to 0 as a [yolo] layer's does; a stated one is replaced
    from isu_validate.reference.detector import _keep_low_scores
    assert _keep_low_scores("[region]\nthresh = .6\nclasses=2\n[yolo]\nclasses=2\n") == (
        "[region]\nthresh=0\nclasses=2\n[yolo]\nthresh=0\nclasses=2\n")
    # the digest covers all three files: other class names are another detector
    other = darknet_detector(tmp_path / "b", names=("person", "cell phone", "cup"))
    assert open_detector(other).sha256 != detector.sha256
    assert digest_of(cfg) == detector.sha256 and digest_of(other) == open_detector(other).sha256   # without running
    # coco.names beside the cfg serves when FILE.names is absent
    coco = darknet_detector(tmp_path / "c", names_file="coco.names")
    assert open_detector(coco).names == ["person", "cell phone"]


def test_bad_darknet_files_are_refused_with_what_is_wrong(tmp_path):
    cfg = darknet_detector(tmp_path / "a")
    cfg.with_suffix(".weights").unlink()
    with pytest.raises(InputError, match="three files side by side.*missing: standin.weights"):
        open_detector(cfg)
    cfg = darknet_detector(tmp_path / "b", side=32)
    cfg.write_text(cfg.read_text().replace("height=32", "height=24"))
    with pytest.raises(InputError, match="needs a square input"):
        open_detector(cfg)
    cfg = darknet_detector(tmp_path / "c")
    cfg.with_suffix(".names").write_text("person\ncell phone\ncup\n")    # names that are not its classes
    with pytest.raises(InputError, match="rows have 7 values, not 5 \\+ 3 classes"):
        open_detector(cfg)
    cfg = darknet_detector(tmp_path / "d")
    weights = cfg.with_suffix(".weights")
    weights.write_bytes(weights.read_bytes()[:-8])                      # cut short: OpenCV alone would read it
    with pytest.raises(InputError, match="standin.weights holds 82 values after its header, and the layers of "
                                         "standin.cfg need 84"):
        open_detector(cfg)
    cfg.write_text("[net]\nwidth=32\nheight=32\n\n[nonsense]\nsize=1\n")
    with pytest.raises(InputError, match="OpenCV cannot read it as a darknet network"):
        open_detector(cfg)


def test_tiles_find_a_phone_too_small_for_the_whole_frame(tmp_path):
    cfg = darknet_detector(tmp_path / "a")
    whole = FrameDetector.open(cfg, {"phone_position": "cell phone"}, tiles=1)
    tiled = FrameDetector.open(cfg, {"phone_position": "cell phone"}, tiles=2)
    small, large = painted(8), painted(24)
    assert whole.log_odds(small, ["phone_position"])["phone_position"] < -3      # 8 px at 32/640: missed
    assert tiled.log_odds(small, ["phone_position"])["phone_position"] > 3       # its tile, scaled up, finds it
    assert tiled.log_odds(large, ["phone_position"]) == whole.log_odds(large, ["phone_position"])
    frame = painted(8)
    parts = views(frame, 2)
    assert len(parts) == 5 and parts[0] is frame and parts[4].shape == (288, 384, 3)
    assert np.array_equal(parts[4], frame[192:, 256:]) and views(frame, 1) == [frame]
    with pytest.raises(InputError, match="--detector-tiles 3: 1 .* or 2"):
        FrameDetector.open(cfg, {"phone_position": "cell phone"}, tiles=3)


def test_a_model_folder_carries_a_darknet_detector_and_reads_it_as_fitted(tmp_path):
    cfg = darknet_detector(tmp_path / "src")
    frame_detector = FrameDetector.open(cfg, {"phone_position": "cell phone"})
    assert frame_detector.detector.copy_into(tmp_path / "model") == "detector.cfg"
    assert sorted(p.name for p in (tmp_path / "model").iterdir()) == ["detector.cfg", "detector.names",
                                                                       "detector.weights"]
    about = frame_detector.describe()
    assert about["file"] == "detector.cfg" and about["tiles"] == 2 and about["named"] == str(cfg)
    copy = open_in_model(tmp_path / "model", about)
    assert copy.detector.sha256 == about["sha256"] and copy.tiles == 2
    frame = painted(8)
    assert copy.log_odds(frame, ["phone_position"]) == frame_detector.log_odds(frame, ["phone_position"])
    # a model fitted before tiles existed read the whole frame only
    assert open_in_model(tmp_path / "model", {k: v for k, v in about.items() if k != "tiles"}).tiles == 1


def test_the_built_in_yolov4_tiny_opens_and_scores_a_frame():
    detector = FrameDetector.open("yolov4-tiny", {"phone_position": "cell phone"})
    about = detector.describe()
    assert about["input"] == 416 and about["named"] == "yolov4-tiny" and "public domain" in about["licence"]
    assert len(detector.detector.names) == 80 and detector.detector.names[67] == "cell phone"
    assert digest_of("yolov4-tiny") == detector.detector.sha256
    z = detector.log_odds(painted(200, (90, 90, 90)), ["phone_position"])["phone_position"]
    assert np.isfinite(z) and z < 0          # a grey square on black is no phone
