"""``transfer``: labelled real photo sets read in four layouts, label maps, the scores' hard cases, and the
command end to end on the shipped reference ISU (real photographs: scikit-image's, labelled here)."""
import json

import numpy as np
import pytest
from PIL import Image

from isu_validate.cli import main
from isu_validate.errors import InputError
from isu_validate.realphotos import label_photos, load_label_map, read_photo_set
from isu_validate.space import load_space
from isu_validate.reference.model import default_model_dir
from isu_validate.transfer.scores import Answer, balanced_accuracy, score

SPACE = load_space("isu-paper")


def _photos():
    from skimage import data
    return [data.astronaut(), data.coffee(), data.chelsea(), data.rocket(), data.immunohistochemistry(),
            data.hubble_deep_field()]


def _save(path, rgb, size=(96, 72)):
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(rgb).resize(size).save(path)


@pytest.fixture(scope="module")
def class_set(tmp_path_factory):
    root = tmp_path_factory.mktemp("classes")
    for i, rgb in enumerate(_photos()):
        _save(root / "set" / f"c{i % 2}" / f"img{i}.jpg", rgb)
    (root / "map.toml").write_text('[classes.c0]\nphone_position = "NO"\nseat_belt = "YES"\n'
                                   '[classes.c1]\nphone_position = "P3"\n')
    return root


def _write_map(tmp_path, text):
    path = tmp_path / "map.toml"
    path.write_text(text)
    return path


# ---- layouts

def test_class_folders_read_each_folder_as_a_class(class_set):
    photo_set = read_photo_set(class_set / "set")
    assert photo_set.layout == "classes"
    assert sorted((p.path.name, p.classes) for p in photo_set.photos)[:2] == [("img0.jpg", ("c0",)),
                                                                             ("img1.jpg", ("c1",))]


def test_yolo_boxes_in_pixels_with_splits_and_background_images(tmp_path):
    rgb = _photos()[0]
    _save(tmp_path / "train" / "images" / "a.jpg", rgb, (200, 100))
    _save(tmp_path / "valid" / "images" / "b.jpg", rgb, (200, 100))
    (tmp_path / "train" / "labels").mkdir(parents=True)
    (tmp_path / "train" / "labels" / "a.txt").write_text("1 0.5 0.5 0.2 0.4\n0 0.1 0.1 0.2 0.2\n")
    (tmp_path / "data.yaml").write_text("names: ['seatbelt', 'phone']\n")
    photo_set = read_photo_set(tmp_path)
    by_name = {p.path.name: p for p in photo_set.photos}
    assert photo_set.layout == "yolo" and set(by_name) == {"a.jpg", "b.jpg"}
    assert [(b.label, b.xyxy) for b in by_name["a.jpg"].boxes] == [("phone", (80, 30, 120, 70)),
                                                                   ("seatbelt", (0, 0, 40, 20))]
    assert by_name["b.jpg"].boxes == () and "no label file" in photo_set.notes[0]


def test_yolo_label_naming_an_unknown_class_is_an_error(tmp_path):
    _save(tmp_path / "images" / "a.jpg", _photos()[0])
    (tmp_path / "labels").mkdir()
    (tmp_path / "labels" / "a.txt").write_text("3 0.5 0.5 0.2 0.2\n")
    (tmp_path / "data.yaml").write_text("names: {0: phone}\n")
    with pytest.raises(InputError, match="class 3 is not in data.yaml"):
        read_photo_set(tmp_path)


def test_coco_and_csv_layouts(tmp_path):
    _save(tmp_path / "coco" / "x.jpg", _photos()[1], (100, 80))
    (tmp_path / "coco" / "_annotations.coco.json").write_text(json.dumps({
        "images": [{"id": 1, "file_name": "x.jpg", "width": 100, "height": 80}],
        "categories": [{"id": 5, "name": "phone"}],
        "annotations": [{"id": 1, "image_id": 1, "category_id": 5, "bbox": [10, 20, 30, 40]}]}))
    coco = read_photo_set(tmp_path / "coco")
    assert coco.layout == "coco" and coco.photos[0].boxes[0].xyxy == (10, 20, 40, 60)
    _save(tmp_path / "csv" / "c6" / "y.jpg", _photos()[2])
    (tmp_path / "csv" / "list.csv").write_text("subject,classname,img\np1,c6,y.jpg\np1,c6,gone.jpg\n")
    assert read_photo_set(tmp_path / "csv").layout == "classes"      # class folders first; the CSV beside them
    listed = read_photo_set(tmp_path / "csv", "csv")
    assert listed.layout == "csv" and listed.photos[0].classes == ("c6",) and "not found" in listed.notes[0]


def test_a_folder_of_nothing_names_the_layouts(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="cannot tell the layout"):
        read_photo_set(tmp_path / "empty")


# ---- label maps

def test_label_map_takes_options_and_values_and_names_choices(tmp_path):
    m = load_label_map(_write_map(tmp_path, '[classes.c1]\nphone_position = "P3"\n[classes.c0]\n'
                                             'phone_position = "NO"\n'), SPACE)
    assert m.classes == {"c1": {"phone_position": "YES"}, "c0": {"phone_position": "NO"}}
    with pytest.raises(InputError, match="is not a feature of space 'isu-paper'; map one of: driver_gender"):
        load_label_map(_write_map(tmp_path, '[classes.c1]\nphone = "YES"\n'), SPACE)
    with pytest.raises(InputError, match=r"neither an answer option \(YES, NO\)"):
        load_label_map(_write_map(tmp_path, '[classes.c1]\nseat_belt = "MAYBE"\n'), SPACE)
    with pytest.raises(InputError, match="not asked of a SUT"):
        load_label_map(_write_map(tmp_path, '[classes.c1]\nexternal_light = "LOW"\n'), SPACE)
    with pytest.raises(InputError, match="no .boxes.NAME. maps"):
        load_label_map(_write_map(tmp_path, '[classes.c1]\nseat_belt = "NO"\n[absent]\nseat_belt = "YES"\n'), SPACE)


def test_absence_of_boxes_and_conflicting_labels(tmp_path):
    from isu_validate.realphotos.layouts import Box, Photo, PhotoSet

    m = load_label_map(_write_map(tmp_path, '[boxes.phone]\nphone_position = "YES"\n[boxes.belt]\n'
                                             'seat_belt = "YES"\n[boxes.nobelt]\nseat_belt = "NO"\n'
                                             '[absent]\nphone_position = "NO"\n'), SPACE)
    photos = [Photo(tmp_path / "a.jpg", boxes=(Box("phone", (0, 0, 1, 1)), Box("belt", (0, 0, 1, 1)))),
              Photo(tmp_path / "b.jpg", boxes=(Box("belt", (0, 0, 1, 1)), Box("nobelt", (0, 0, 1, 1)))),
              Photo(tmp_path / "c.jpg", boxes=(Box("face", (0, 0, 1, 1)),))]
    photo_set = PhotoSet(tmp_path, "yolo", photos)
    with pytest.raises(InputError, match="b.jpg: its labels answer seat_belt both NO and YES"):
        label_photos(photo_set, m)
    labelled = label_photos(photo_set, m, skip_conflicts=True)
    answers = {p.path.name: p.answers for p in labelled.photos}
    assert answers == {"a.jpg": {"phone_position": "YES", "seat_belt": "YES"}, "b.jpg": {"phone_position": "NO"},
                       "c.jpg": {"phone_position": "NO"}}
    assert labelled.conflicts == {"seat_belt": 1} and labelled.unmapped == {"face": 1}


# ---- scores: hard cases

def test_balanced_accuracy_agrees_with_scikit_learn_and_the_majority_baseline():
    from sklearn.metrics import balanced_accuracy_score
    rng = np.random.default_rng(0)
    truth = rng.choice(["YES", "NO"], 200, p=[0.8, 0.2])
    said = np.where(rng.random(200) < 0.7, truth, rng.choice(["YES", "NO"], 200))
    assert balanced_accuracy(truth, said) == pytest.approx(balanced_accuracy_score(truth, said))
    always = score([Answer(t, "YES") for t in truth], ("YES", "NO"))
    assert always["balanced_accuracy"] == pytest.approx(0.5)
    assert always["accuracy"] == pytest.approx(always["majority_baseline"]["accuracy"])


def test_scores_of_one_class_ties_and_nothing_answered():
    one = score([Answer("YES", "YES"), Answer("YES", "NO")], ("YES", "NO"))
    assert one["balanced_accuracy"] == 0.5 and one["auc"] is None and one["majority_baseline"]["balanced_accuracy"] == 1
    tied = score([Answer("YES", "YES", 0.5), Answer("NO", "NO", 0.5)] * 3, ("YES", "NO"))
    assert tied["auc"] == 0.5 and tied["balanced_accuracy"] == 1.0 and tied["balanced_accuracy_ci95"] == [1.0, 1.0]
    silent = score([Answer("YES", None), Answer("NO", None)], ("YES", "NO"))
    assert silent["accuracy"] is None and silent["unanswered"] == 2 and silent["said_counts"] == {"(unanswered)": 2}
    garbage = score([Answer("YES", "MAYBE"), Answer("NO", "NO")], ("YES", "NO"))
    assert garbage["confusion"]["labels"] == ["YES", "NO", "MAYBE"] and garbage["accuracy"] == 0.5


def test_answers_per_label_count_a_photo_under_each_of_its_labels_and_leave_the_unanswered_out_of_the_share():
    from isu_validate.transfer.scores import said_by_label
    rows = [(("drinking",), "NO", "YES", None), (("drinking",), "NO", "NO", None), (("drinking",), "NO", None, None),
            (("phone", "seatbelt"), "YES", "YES", None), (("seatbelt",), "NO", "NO", None), ((), "NO", "NO", None)]
    table = said_by_label(rows, "YES")
    assert list(table) == ["(no label)", "drinking", "phone", "seatbelt"]
    assert table["drinking"] == {"n": 3, "truth": {"NO": 3}, "said": {"(unanswered)": 1, "NO": 1, "YES": 1},
                                 "said_positive": 0.5, "auc_against_other_side": None}   # no probabilities
    assert table["seatbelt"]["n"] == 2 and table["seatbelt"]["said_positive"] == 0.5
    assert said_by_label([(("x",), "NO", None, None)], "YES")["x"]["said_positive"] is None   # nothing answered
    # a garbage answer ("MAYBE") is a third answer, not a third option: the yes/no line is still printed
    from isu_validate.transfer.scores import format_said_by_label
    sc = score([Answer("NO", "MAYBE"), Answer("NO", "YES"), Answer("YES", "YES")], ("YES", "NO"))
    assert sc["confusion"]["labels"] == ["YES", "NO", "MAYBE"]
    lines = format_said_by_label("set", {**sc, "said_by_label": said_by_label(
        [(("drinking",), "NO", "MAYBE", None), (("drinking",), "NO", "YES", None), (("phone",), "YES", "YES", None)],
        "YES")})
    assert lines[0] == "  set: said YES per label (* truly YES; n)" and "drinking 50% (2)" in lines[1]
    assert "phone* 100% (1)" in lines[1]


def test_each_label_is_ranked_against_the_other_side_and_a_label_ranked_above_the_positives_reads_under_half():
    from isu_validate.transfer.scores import format_said_by_label, said_by_label
    rows = [(("texting",), "YES", "YES", 0.9), (("texting",), "YES", "YES", 0.7), (("talking",), "YES", "NO", 0.4),
            (("drinking",), "NO", "YES", 0.95), (("drinking",), "NO", "YES", 0.8),     # above every positive but one
            (("safe",), "NO", "NO", 0.1), (("safe",), "NO", "NO", 0.4),                # a tie with "talking"
            (("safe",), "NO", None, None)]                                            # unanswered: left out
    table = said_by_label(rows, "YES")
    assert table["drinking"]["auc_against_other_side"] == pytest.approx(1 / 6, abs=1e-4)   # 1 pair of 6 is won
    assert table["safe"]["auc_against_other_side"] == pytest.approx(5.5 / 6, abs=1e-4)   # the tie counts half
    assert table["texting"]["auc_against_other_side"] == pytest.approx(5 / 8, abs=1e-4)   # against all four negatives
    assert table["talking"]["auc_against_other_side"] == pytest.approx(1.5 / 4, abs=1e-4)
    # a mixed label (a box class on photos of both sides) stands for its majority; a tie for the negatives
    mixed = said_by_label([(("belt",), "YES", "YES", 0.9), (("belt",), "NO", "NO", 0.2), ((), "NO", "NO", 0.5)], "YES")
    assert mixed["belt"]["auc_against_other_side"] == 1.0   # its NO photo (0.2) below the one YES photo (0.9)
    # one side empty: no AUC, never a division by zero
    assert said_by_label([(("x",), "NO", "NO", 0.3)], "YES")["x"]["auc_against_other_side"] is None
    # a probability missing where it is needed: no AUC rather than one over part of the photos
    assert said_by_label([(("x",), "NO", "NO", None), (("y",), "YES", "YES", 0.6)], "YES")["y"][
        "auc_against_other_side"] is None
    sc = score([Answer(t, s, p) for _, t, s, p in rows[:-1]], ("YES", "NO"))
    lines = format_said_by_label("set", {**sc, "said_by_label": table})
    assert "AUC against the other side" in lines[0]
    assert "drinking 100% (2, AUC 0.17)" in " ".join(lines) and "safe 0% (3, AUC 0.92)" in " ".join(lines)


def test_bootstrap_interval_is_seeded_and_holds_the_estimate():
    answers = [Answer(t, s) for t, s in [("YES", "YES")] * 30 + [("YES", "NO")] * 10 + [("NO", "NO")] * 8
               + [("NO", "YES")] * 12]
    a, b = score(answers, ("YES", "NO"), seed=3), score(answers, ("YES", "NO"), seed=3)
    assert a["balanced_accuracy_ci95"] == b["balanced_accuracy_ci95"]
    low, high = a["balanced_accuracy_ci95"]
    assert low < a["balanced_accuracy"] < high
    assert a["recall"]["YES"]["rate"] == 0.75 and a["recall"]["NO"]["ci95"][0] < 0.4 < a["recall"]["NO"]["ci95"][1]


# ---- the command, end to end on the shipped reference ISU

def test_transfer_end_to_end_resumes_and_refuses_other_settings(class_set, tmp_path, capsys, few_torch_threads):
    import shutil
    shutil.copytree(class_set / "set", tmp_path / "set")
    (tmp_path / "set" / "c0" / "broken.jpg").write_bytes(b"\xff\xd8 not a jpeg")
    out = tmp_path / "t"
    args = ["transfer", str(tmp_path / "set"), "--labels", str(class_set / "map.toml"), "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "phone_position" in printed and "renders (isu-blender" in printed
    summary = json.loads((out / "summary.json").read_text())
    phone = summary["sets"]["set"]["scores"]["phone_position"]
    assert phone["n"] == 7 and phone["unanswered"] == 1          # the broken photo: an error, never a failure
    assert phone["auc"] is not None
    rates = [r["rate"] for r in phone["recall"].values()]
    assert phone["balanced_accuracy"] == pytest.approx(sum(rates) / len(rates))   # the mean of the recalls
    card = json.loads((default_model_dir() / "model_card.json").read_text())
    hidden = card.get("hidden_from_camera", {}).get("held_out", {}).get("phone_position", 0)
    assert summary["renders"]["scores"]["phone_position"]["n"] == 200 - hidden   # the shipped model's held-out renders
    assert "zero_shot" not in summary["settings"] and "zero_shot" not in summary
    assert summary["sets"]["set"]["scores"]["seat_belt"]["n"] == 4      # only c0 says the belt
    by_label = phone["said_by_label"]                             # per class folder: what was said
    assert {k: v["n"] for k, v in by_label.items()} == {"c0": 4, "c1": 3}
    assert by_label["c0"]["truth"] == {"NO": 4} and by_label["c0"]["said"].get("(unanswered)") == 1
    assert by_label["c1"]["said_positive"] == pytest.approx(phone["recall"]["YES"]["rate"])   # c1 alone is YES
    assert "set: said YES per label (* truly YES; n)" in printed and " c1* " in printed
    assert "set: answers per label of the set" in (out / "report.html").read_text()
    lines = [json.loads(x) for x in (out / "answers.jsonl").read_text().splitlines()]
    assert {x["set"] for x in lines} == {"set", "renders"}
    html = (out / "report.html").read_text()
    for feature, scores in summary["sets"]["set"]["scores"].items():   # a gallery exactly where answers were wrong
        assert (f"Wrong answers on set: {feature}" in html) == (scores["accuracy"] < 1.0), feature
    assert main(args) == 0                                       # the same again: every reply from the cache
    again = [json.loads(x) for x in (out / "answers.jsonl").read_text().splitlines() if '"set": "set"' in x]
    assert all(x["cached"] for x in again if not x["error"])
    capsys.readouterr()
    assert main(args + ["--limit", "2"]) == 2                    # another measurement: refused, nothing written
    assert "made with other settings (limit: (default) then, 2 now)" in capsys.readouterr().err


# ---- zero-shot: does the object read as itself to a photo-trained classifier?

def test_the_zero_shot_crops_tile_the_frame_in_halves_and_thirds():
    from isu_validate.recognition.objects import anywhere_crops
    rgb = (np.arange(60 * 90 * 3).reshape(60, 90, 3) % 251).astype(np.uint8)
    crops = anywhere_crops(rgb)
    assert len(crops) == 25
    assert [c.shape[:2] for c in crops] == [(30, 45)] * 9 + [(20, 30)] * 16
    halves = [(y, x) for y in (0, 15, 30) for x in (0, 22, 45)]         # overlapping, corner to corner
    thirds = [(y, x) for y in (0, 13, 27, 40) for x in (0, 20, 40, 60)]
    for crop, (y, x), (h, w) in zip(crops, halves + thirds, [(30, 45)] * 9 + [(20, 30)] * 16, strict=True):
        assert (crop == rgb[y:y + h, x:x + w]).all()
    covered = np.zeros((60, 90), bool)
    for y, x in thirds:
        covered[y:y + 20, x:x + 30] = True
    assert covered.all()


def test_the_zero_shot_auc_says_which_frames_show_the_thing(tmp_path, monkeypatch):
    from isu_validate.transfer.ask import Item
    from isu_validate.transfer.zero_shot import format_zero_shot, zero_shot_scores

    class Brightness:   # stands in for the classifier: the brighter the frame, the more "phone"
        def __init__(self, device):
            pass

        def anywhere(self, rgb, obj):
            assert obj == "phone"
            return float(rgb.mean())

    class Darkness:     # stands in for the detector: the darker the frame, the surer "cell phone"
        classes = {"phone_position": "cell phone"}

        def log_odds(self, rgb, features):
            assert features == ["phone_position"]
            return {"phone_position": 10.0 - float(rgb.mean()) / 10}

    monkeypatch.setattr("isu_validate.recognition.objects.ObjectRecogniser", Brightness)
    monkeypatch.setattr("isu_validate.reference.detector.FrameDetector.open", lambda spec, classes: Darkness())
    frames = {}
    for level in (10, 20, 200, 210):
        frames[level] = tmp_path / f"{level}.png"
        Image.fromarray(np.full((8, 8, 3), level, np.uint8)).save(frames[level])

    def items(yes, no, grey=()):
        return ([Item(f"y{v}", frames[v], {"phone_position": "YES"}) for v in yes]
                + [Item(f"n{v}", frames[v], {"phone_position": "NO", "seat_belt": "YES"}) for v in no])
    out = zero_shot_scores({"shows": items((200, 210), (10, 20)), "backwards": items((10, 20), (200, 210)),
                            "ties": items((20,), (20,)), "no negatives": items((200,), ())},
                           SPACE, ["phone_position", "seat_belt"], "cpu")
    assert out["shows"]["phone_position"]["auc"] == 1.0 and out["backwards"]["phone_position"]["auc"] == 0.0
    assert out["ties"]["phone_position"]["auc"] == 0.5 and out["no negatives"]["phone_position"]["auc"] is None
    assert out["shows"]["phone_position"]["median_positive"] == pytest.approx(205.0)
    assert set(out["shows"]) == {"phone_position"}       # no object stands for a seat belt: not scored
    assert zero_shot_scores({"x": items((200,), (10,))}, SPACE, ["seat_belt"], "cpu") == {}
    # the detector's own scores on the same frames, beside the classifier's
    seen = out["shows"]["phone_position"]["detector"]
    assert seen["name"] == "yolov4-tiny" and seen["class"] == "cell phone" and seen["auc"] == 0.0
    assert out["backwards"]["phone_position"]["detector"]["auc"] == 1.0
    assert seen["median_positive"] == pytest.approx(np.mean([1 / (1 + np.exp(z)) for z in (10.0, 11.0)]))
    # not installed: the classifier's score stands, and the summary and the printed line say why
    def missing(spec, classes):
        raise InputError("the built-in detector yolov4-tiny is not installed; run make setup")
    monkeypatch.setattr("isu_validate.reference.detector.FrameDetector.open", missing)
    out = zero_shot_scores({"shows": items((200, 210), (10, 20))}, SPACE, ["phone_position"], "cpu")
    assert out["shows"]["phone_position"]["auc"] == 1.0
    assert out["shows"]["phone_position"]["detector"] == {
        "name": "yolov4-tiny", "unavailable": "the built-in detector yolov4-tiny is not installed; run make setup"}
    assert format_zero_shot(out)[1] == ("zero-shot detector yolov4-tiny, shows, phone_position: not read (the "
                                        "built-in detector yolov4-tiny is not installed; run make setup)")


def test_transfer_zero_shot_scores_the_real_photos_with_the_real_classifier(class_set, tmp_path, capsys,
                                                                           few_torch_threads):
    import shutil
    shutil.copytree(class_set / "set", tmp_path / "set")
    (tmp_path / "set" / "c1" / "broken.jpg").write_bytes(b"\xff\xd8 not a jpeg")   # left out and counted
    out = tmp_path / "z"
    assert main(["transfer", str(tmp_path / "set"), "--labels", str(class_set / "map.toml"), "--zero-shot",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "zero-shot phone anywhere (ImageNet classes, no training), set, phone_position: AUC" in printed
    assert "(n 3 with, 3 without, 1 unreadable)" in printed
    # and the built-in detector, read as a window model reads it
    assert "zero-shot detector yolov4-tiny 'cell phone' (COCO photos, no training from renders), set, " \
           "phone_position: AUC" in printed
    summary = json.loads((out / "summary.json").read_text())
    row = summary["zero_shot"]["set"]["phone_position"]
    assert (row["n_positive"], row["n_negative"], row["unreadable"]) == (3, 3, 1) and 0.0 <= row["auc"] <= 1.0
    assert 0.0 <= row["median_positive"] <= 1.0 and summary["settings"]["zero_shot"] is True
    seen = row["detector"]
    assert seen["class"] == "cell phone" and 0.0 <= seen["auc"] <= 1.0 and 0.0 <= seen["median_negative"] <= 1.0
    report = (out / "report.html").read_text()
    assert "Does the object read as itself? (zero-shot, no training)" in report and "cell phone (yolov4-tiny)" in report


def test_transfer_escapes_what_the_labels_and_sut_said(tmp_path, few_torch_threads):
    root = tmp_path / "set"
    for label in ("<script>x", "<b>y"):   # the same photo labelled both ways: one answer is wrong, and shown
        _save(root / label / "a.jpg", _photos()[0])
    m = _write_map(tmp_path, '[classes."<script>x"]\nphone_position = "YES"\n[classes."<b>y"]\nphone_position = "NO"\n')
    out = tmp_path / "t"
    assert main(["transfer", str(root), "--labels", str(m), "--out", str(out)]) == 0
    html = (out / "report.html").read_text()
    assert "<script>x" not in html and "<b>y" not in html
    assert ("&lt;script&gt;x/a.jpg" in html) != ("&lt;b&gt;y/a.jpg" in html)


# ---- recognise on real photographs without render labels

def test_recognise_reads_a_labelled_real_set_beside_nothing_else(tmp_path, few_torch_threads):
    from skimage import data
    root = tmp_path / "yolo"
    _save(root / "images" / "astronaut.jpg", data.astronaut(), (256, 256))
    _save(root / "images" / "coffee.jpg", data.coffee(), (300, 200))
    (root / "labels").mkdir()
    (root / "labels" / "coffee.txt").write_text("0 0.5 0.5 0.6 0.8\n")     # the cup, labelled as a phone here
    (root / "data.yaml").write_text("names: [phone]\n")
    m = _write_map(tmp_path, '[boxes.phone]\nphone_position = "YES"\n[absent]\nphone_position = "NO"\n')
    out = tmp_path / "rec"
    assert main(["recognise", "--real", str(root), "--labels", str(m), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    rows = {r["measure"]: r for r in summary["rows"] if r["split"] == "all" and r["kind"] == "real"}
    assert summary["frames"]["real_frames"] == 2
    assert rows["face found"]["n"] == 2 and rows["face found"]["hits"] == 1     # the astronaut's, not the cup's
    assert rows["any face read happy"]["n"] == 1 and rows["any face read happy"]["hits"] == 1
    assert rows["phone top-5"]["n"] == 1                                        # read in its box
    assert main(["recognise", "--labels", str(m), "--out", str(tmp_path / "r2")]) == 2   # --labels needs --real


# ---- bench transfer

def test_bench_transfer_recipes_parse_and_a_model_recipe_runs(class_set, tmp_path, capsys, few_torch_threads):
    from isu_validate.bench.transfer import parse_recipe
    assert parse_recipe("side=train:camera=cam.toml,n=50").options == {"camera": "cam.toml", "n": 50}
    assert parse_recipe("v=train:camera_jitter=pos=0.05,angle=5,sensor_effects=mild,n=20").options == {
        "camera_jitter": "pos=0.05,angle=5", "sensor_effects": "mild", "n": 20}
    assert parse_recipe("m=train:camera=passenger-side,camera_mix=default,passenger-door,seed=1").options == {
        "camera": "passenger-side", "camera_mix": "default,passenger-door", "seed": 1}
    assert parse_recipe("r5=model:/m/r5,renders=/m/w/held-out").options == {"model": "/m/r5",
                                                                            "renders": "/m/w/held-out"}
    for bad, why in [("x", "must read NAME="), ("a=train:lens=3", "KEY one of"), ("a=train:n=many", "n must be int")]:
        with pytest.raises(InputError, match=why):
            parse_recipe(bad)
    from isu_validate.reference.model import default_model_dir
    out = tmp_path / "bench"
    assert main(["bench", "transfer", str(class_set / "set"), "--labels", str(class_set / "map.toml"),
                 "--recipe", f"shipped=model:{default_model_dir()}", "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "shipped: model" in table and "real set" in table and "own held-out renders" in table
    assert "set, phone_position: said YES per label" in table       # which feature each per-label line is about
    row = json.loads((out / "bench.json").read_text())[0]
    assert row["scores"]["set"]["phone_position"]["n"] == 6 and row["scores"]["renders"]["phone_position"] > 0.9


def test_a_trained_recipe_is_reused_only_for_the_rig_files_it_was_made_with(tmp_path):
    """Editing a camera file changes what a recipe renders: its kept model is refused, not silently reused."""
    from argparse import Namespace

    from isu_validate.bench.transfer import _train, parse_recipe, recipe_settings
    from isu_validate.paths import rigs_dir
    rig = tmp_path / "cam.toml"
    rig.write_text((rigs_dir() / "cameras" / "passenger-side.toml").read_text())
    recipe, args = parse_recipe(f"side=train:camera={rig},n=4,held_out=2"), Namespace(preset="draft", n=4,
                                                                                      held_out=2, seed=0)
    options, made = recipe_settings(recipe, args)
    assert options["camera"] == str(rig) and options["n"] == 4 and recipe_settings(recipe, args)[1] == made
    assert json.loads(made)["renderer"] and json.loads(made)["camera_hash"]
    rig.write_text(rig.read_text().replace("fx = 420.0", "fx = 400.0"))
    assert json.loads(recipe_settings(recipe, args)[1])["camera_hash"] != json.loads(made)["camera_hash"]
    folder = tmp_path / "side"
    folder.mkdir()
    (folder / "recipe.json").write_text(made)   # kept from before the rig was edited
    with pytest.raises(InputError, match=f"rig files.*delete {folder}"):
        _train(recipe, folder, args)


def test_a_trained_recipe_kept_from_another_head_fit_is_refused(tmp_path):
    """A model fitted before the heads clipped their features would measure that fit: refused, not reused."""
    from argparse import Namespace

    from isu_validate.bench.transfer import _train, parse_recipe, recipe_settings
    from isu_validate.reference.heads import CLIP_SIGMA
    recipe, args = parse_recipe("side=train:n=4,held_out=2"), Namespace(preset="draft", n=4, held_out=2, seed=0)
    made = json.loads(recipe_settings(recipe, args)[1])
    assert made["heads"]["clip_sigma"] == CLIP_SIGMA
    folder = tmp_path / "side"
    folder.mkdir()
    before = {k: v for k, v in made.items() if k != "heads"}
    (folder / "recipe.json").write_text(json.dumps(before, sort_keys=True))
    with pytest.raises(InputError, match=f"fitted otherwise.*unclipped.*delete {folder / 'model'} and "
                                         f"{folder / 'recipe.json'} to fit them again on its renders"):
        _train(recipe, folder, args)
    assert not (folder / "model").exists()          # nothing made, nothing rendered
    (folder / "recipe.json").write_text("{damaged")
    with pytest.raises(InputError, match=f"other settings, renderer or rig files.*delete {folder} to make it again"):
        _train(recipe, folder, args)


# ---- clusters: frames of one driver are near-twins

def test_group_bootstrap_is_wider_than_the_photo_bootstrap_when_groups_are_alike():
    answers = []
    for g in range(8):   # each driver all right or all wrong, 20 frames each
        right = g % 2 == 0
        answers += [Answer(t, t if right else ("NO" if t == "YES" else "YES"), group=f"p{g}")
                    for t in ["YES", "NO"] * 10]
    photo = score([Answer(a.truth, a.said) for a in answers], ("YES", "NO"))
    grouped = score(answers, ("YES", "NO"))
    assert grouped["bootstrap_unit"] == "group" and photo["bootstrap_unit"] == "photo"
    width = lambda s: s["balanced_accuracy_ci95"][1] - s["balanced_accuracy_ci95"][0]  # noqa: E731
    assert width(grouped) > 2 * width(photo)
    one = score([Answer("YES", "YES", group="p0"), Answer("NO", "NO", group="p0")], ("YES", "NO"))
    assert one["balanced_accuracy_ci95"] is None        # one cluster: no interval


def test_groups_file_is_read_by_path_or_name_and_must_cover_every_photo(class_set, tmp_path):
    from isu_validate.realphotos.groups import read_groups
    from isu_validate.transfer import TransferSettings
    from isu_validate.transfer.measure import read_real_sets
    csv_file = tmp_path / "subjects.csv"
    csv_file.write_text("image,subject\nc0/img0.jpg,p1\nimg2.jpg,p2\nc0/img4.jpg,p1\n")
    assert read_groups(csv_file)["img0.jpg"] == "p1"
    settings = TransferSettings((str(class_set / "set"),), (str(class_set / "map.toml"),),
                                groups={"set": str(csv_file)})
    with pytest.raises(InputError, match="names no group for 3 of its labelled photos"):
        read_real_sets(settings, SPACE)
    csv_file.write_text("image,driver\n" + "".join(f"img{i}.jpg,p{i % 3}\n" for i in range(6)))
    items = read_real_sets(settings, SPACE)[0].items
    assert sorted(i.group for i in items) == ["p0", "p0", "p1", "p1", "p2", "p2"]
    with pytest.raises(InputError, match="--groups names other, which is no real set"):
        read_real_sets(TransferSettings(settings.real, settings.labels, groups={"other": str(csv_file)}), SPACE)
    (tmp_path / "bad.csv").write_text("file,who\nx,y\n")
    with pytest.raises(InputError, match="needs an image column .image, img.* and a group column"):
        read_groups(tmp_path / "bad.csv")


def test_a_fine_tuned_recipe_is_another_recipe_and_one_without_reads_as_before(tmp_path):
    """``fine_tune=BLOCKS`` is part of what a recipe made; a recipe without it keeps the recipe.json it had."""
    from argparse import Namespace

    from isu_validate.bench.transfer import _train, parse_recipe, recipe_settings
    args = Namespace(preset="draft", n=4, held_out=2, seed=0)
    plain = parse_recipe("side=train:n=4,held_out=2")
    tuned = parse_recipe("side=train:n=4,held_out=2,fine_tune=6")
    assert tuned.options["fine_tune"] == 6
    assert "fine_tune" not in json.loads(recipe_settings(plain, args)[1])
    assert json.loads(recipe_settings(tuned, args)[1])["fine_tune"] == 6
    folder = tmp_path / "side"
    folder.mkdir()
    (folder / "recipe.json").write_text(recipe_settings(plain, args)[1])   # kept from the frozen recipe
    with pytest.raises(InputError, match="delete"):
        _train(tuned, folder, args)
    assert not (folder / "model").exists()


def test_a_recipe_with_window_heads_keeps_its_feature_list_whole_and_checks_it(tmp_path):
    from argparse import Namespace

    from isu_validate.bench.transfer import _train, parse_recipe, recipe_settings
    args = Namespace(preset="draft", n=4, held_out=2, seed=0, render_device="cpu", device="cpu")
    both = parse_recipe("side=train:n=4,windows=phone_position,seat_belt,seed=2")
    assert both.options == {"n": 4, "windows": "phone_position,seat_belt", "seed": 2}
    assert "windows" not in json.loads(recipe_settings(parse_recipe("side=train:n=4"), args)[1])
    assert json.loads(recipe_settings(both, args)[1])["windows"] == "phone_position,seat_belt"
    with pytest.raises(InputError, match="answers a yes/no question"):   # refused before anything renders
        _train(parse_recipe("side=train:n=4,windows=tshirt_colour"), tmp_path / "side", args)
    assert not (tmp_path / "side" / "cache").exists()
