"""`agree` on a pairs directory whose every number is known by hand.

The real side is a stand-in (the render shifted, darkened and noised, and labelled as a stand-in
in its sidecar); the SUT is a command-protocol program with fixed answers per image, so the
counts, the rates, the nst rate and the rows of agreement.csv are worked out below by hand."""
import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageDraw

from isu_validate.agree.compare import category, counts
from isu_validate.agree.votes import INVALID, TIED, UNVOTED, VALID, verdict
from isu_validate.cli import main
from isu_validate.space import load_space

SPACE = """
name = "mini"
[features.driver_gender]
type = "categorical"
values = ["MALE", "FEMALE"]
predicted = true
question = "Gender of the driver?"
options = ["MALE", "FEMALE", "NONE"]
[features.seat_belt]
type = "categorical"
values = ["YES", "NO"]
predicted = true
question = "Belt on?"
options = ["YES", "NO", "NONE"]
[features.luggage]
type = "categorical"
values = ["YES", "NO"]
predicted = true
question = "Luggage?"
options = ["YES", "NO"]
[features.luggage_colour]
type = "categorical"
values = ["YELLOW", "ANTHRACITE"]
active_when = { luggage = "YES" }
predicted = true
question = "Luggage colour?"
options = ["YELLOW", "ANTHRACITE", "NONE"]
[features.car_lights]
type = "categorical"
values = ["ON", "OFF"]
"""

# A command-protocol SUT: fixed answers per image (key: <sample>/<file>), a list of answer sets is
# given in turn on repeated calls; "error" makes it fail. Every call is logged.
SUT = r"""
import json, sys
from pathlib import Path
table, log = json.loads(Path(sys.argv[1]).read_text()), Path(sys.argv[2])
req = json.load(sys.stdin)
image = Path(req["image"])
key = "/".join(image.parts[-3:] if image.parent.name == "real" else image.parts[-2:])
with log.open("a") as f:
    f.write(key + "\n")
entry = table[key]
if entry == "error":
    print("model crashed", file=sys.stderr)
    sys.exit(1)
if isinstance(entry, list):
    calls = log.read_text().split().count(key)
    entry = entry[(calls - 1) % len(entry)]
print(json.dumps({"answers": entry}))
"""

M, F = "MALE", "FEMALE"
ANSWERS = {
    # S01: truth MALE, YES, YES, YELLOW
    "S01/sim.png": {"driver_gender": M, "seat_belt": "NO", "luggage": "YES", "luggage_colour": "YELLOW"},
    "S01/real/frame_0000.png": {"driver_gender": M, "seat_belt": "NO", "luggage": "NO", "luggage_colour": "ANTHRACITE"},
    "S01/real/frame_0001.png": [  # three repeats: the majority says FEMALE
        {"driver_gender": F, "seat_belt": "YES", "luggage": "YES", "luggage_colour": "YELLOW"},
        {"driver_gender": M, "seat_belt": "YES", "luggage": "YES", "luggage_colour": "YELLOW"},
        {"driver_gender": F, "seat_belt": "YES", "luggage": "YES", "luggage_colour": "YELLOW"}],
    "S01/nst.png": {"driver_gender": M, "seat_belt": "YES", "luggage": "NO", "luggage_colour": "YELLOW"},
    # S02: truth FEMALE, NO, NO; seat_belt occluded; no luggage answer on the photo
    "S02/sim.png": {"driver_gender": F, "seat_belt": "YES", "luggage": "NO"},
    "S02/real/frame_0000.png": {"driver_gender": M, "seat_belt": "YES"},
    "S02/nst.png": {"driver_gender": M, "seat_belt": "NO", "luggage": "NO"},
    # S03: voted invalid, never asked
    "S03/sim.png": {}, "S03/real/frame_0000.png": {},
    # S04: one broken photo, and the SUT fails on the other
    "S04/sim.png": {"driver_gender": M, "seat_belt": "YES", "luggage": "NO"},
    "S04/real/frame_0001.png": "error",
    # S05 has no real/, S06 comes from another space: never asked
}
SCENES = {
    "S01": {"driver_gender": M, "seat_belt": "YES", "luggage": "YES", "luggage_colour": "YELLOW", "car_lights": "ON"},
    "S02": {"driver_gender": F, "seat_belt": "NO", "luggage": "NO", "car_lights": "OFF"},
    "S03": {"driver_gender": F, "seat_belt": "YES", "luggage": "NO", "car_lights": "OFF"},
    "S04": {"driver_gender": M, "seat_belt": "YES", "luggage": "NO", "car_lights": "ON"},
    "S05": {"driver_gender": M, "seat_belt": "NO", "luggage": "NO", "car_lights": "ON"},
    "S06": {"driver_gender": M, "seat_belt": "NO", "luggage": "NO", "car_lights": "ON"},
}
FRAMES = {"S01": 2, "S02": 1, "S03": 1, "S04": 2, "S05": 0, "S06": 1}


def drawing(seed: int, size=(96, 72)) -> Image.Image:
    rng = np.random.default_rng(seed)
    img = Image.new("RGB", size, tuple(int(v) for v in rng.integers(40, 120, 3)))
    d = ImageDraw.Draw(img)
    for _ in range(4):
        x, y = rng.integers(0, size[0] - 20), rng.integers(0, size[1] - 20)
        d.rectangle([int(x), int(y), int(x + 18), int(y + 14)], fill=tuple(int(v) for v in rng.integers(0, 256, 3)))
    return img


def stand_in(img: Image.Image, seed: int) -> Image.Image:
    """The 'photo': the render moved by two pixels, darker, with noise."""
    a = np.roll(np.asarray(img, np.float32), (1, 2), axis=(0, 1)) * 0.8
    a += np.random.default_rng(seed).normal(0, 6, a.shape)
    return Image.fromarray(np.clip(a, 0, 255).astype(np.uint8))


def make_pairs(root: Path, space_file: Path) -> Path:
    space = load_space(space_file)
    for i, (name, scene) in enumerate(SCENES.items()):
        d = root / name
        d.mkdir(parents=True)
        label = {"test_id": f"g0000-i{i:03d}", "space": "other" if name == "S06" else space.name,
                 "space_hash": space.hash, "scene": scene,
                 "truth": {q.key: q.truth for q in space.questions(scene)}}
        if name == "S02":
            label["occluded"] = ["seat_belt"]
        (d / "scene.json").write_text(json.dumps(label))
        sim = drawing(i)
        sim.save(d / "sim.png")
        if name in ("S01", "S02"):
            drawing(100 + i).save(d / "nst.png")
        if FRAMES[name]:
            (d / "real").mkdir()
        for k in range(FRAMES[name]):
            frame = d / "real" / f"frame_{k:04d}.png"
            stand_in(sim, 10 * i + k).save(frame)
            frame.with_suffix(".json").write_text(json.dumps(
                {"device": "stand-in (test drawing)", "stand_in": True, "exposure_us": None, "iso": None,
                 "timestamp": "2026-11-22T00:00:00+00:00"}))
    (root / "S04" / "real" / "frame_0000.png").write_bytes(b"\x89PNG\r\n\x1a\nbroken")
    # S01 valid (2 yes), S02 tied (1 to 1), S03 invalid (2 no, 1 yes)
    votes = {"a": ["S01=yes", "S02=yes", "S03=no"], "b": ["S01=y", "S02=no", "S03=n"], "c": ["S03=yes"]}
    for annotator, given in votes.items():
        assert main(["agree", "votes", str(root), "--annotator", annotator,
                     *[arg for vote in given for arg in ("--vote", vote)]]) == 0
    return root


@pytest.fixture()
def setup(tmp_path):
    space_file = tmp_path / "mini.toml"
    space_file.write_text(SPACE)
    table, log, program = tmp_path / "answers.json", tmp_path / "calls.log", tmp_path / "sut.py"
    table.write_text(json.dumps(ANSWERS))
    program.write_text(SUT)
    sut = f"command:{sys.executable} {program} {table} {log}"
    return make_pairs(tmp_path / "pairs", space_file), space_file, sut, log


def test_every_number_of_the_summary_by_hand(setup, tmp_path, capsys):
    pairs, space_file, sut, log = setup
    out = tmp_path / "agree"
    code = main(["agree", str(pairs), "--sut", sut, "--space", str(space_file), "--out", str(out),
                 "--feature-cache", str(tmp_path / "fcache"), "--threads", "2"])
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    # sim vs real: S01/frame_0000 bc bw so so; S01/frame_0001 so ro bc bc; S02 so (+ occluded, unanswered)
    assert (s["both_correct"], s["both_wrong"], s["sim_only"], s["real_only"]) == (3, 1, 4, 1)
    assert s["n_features_compared"] == 9 and s["agreement_rate"] == pytest.approx(4 / 9)
    assert s["n_samples"] == 2 and s["n_frames"] == 3
    assert (s["stand_in_frames"], s["real_frames"]) == (3, 0)   # every "photo" here is a stand-in render
    assert s["not_compared"] == {"occluded": 1, "unanswered": 1, "sut_error": 3}   # S04's frame: 3 features
    pf = s["per_feature"]
    assert pf["driver_gender"]["compared"] == 3 and pf["driver_gender"]["agreement_rate"] == pytest.approx(1 / 3)
    assert pf["seat_belt"]["compared"] == 2 and pf["seat_belt"]["occluded"] == 1
    assert pf["luggage"]["unanswered"] == 1 and pf["luggage_colour"]["agreement_rate"] == 0.5
    assert "car_lights" not in pf   # not predicted: never asked
    # nst vs real: S01/frame_0000 bc no bw no; S01/frame_0001 no bc ro bc; S02 bw
    assert s["nst_counts"] == {"both_correct": 3, "both_wrong": 2, "nst_only": 3, "real_only": 1}
    assert s["agreement_rate_nst"] == pytest.approx(5 / 9) and s["n_features_compared_nst"] == 9
    assert s["nst_change"]["rows"] == 9 and s["nst_change"]["change"] == pytest.approx(1 / 9)
    # validity: S01 valid, S02 tied (kept), S03 invalid (left out), three without votes
    v = s["validity"]
    assert (v["valid"], v["invalid"], v["tied"], v["unvoted"]) == (1, 1, 1, 3) and v["rate"] == pytest.approx(1 / 3)
    assert v["invalid_samples"] == ["S03"] and v["tied_samples"] == ["S02"]
    # FID/KID between 2 renders and 3 photos, with the small-n settings reported
    from isu_validate.realism import FeatureExtractor, fid
    features = FeatureExtractor(cache=tmp_path / "fcache").features  # the features agree computed above
    sims = features([pairs / "S01" / "sim.png", pairs / "S02" / "sim.png"])
    reals = features([pairs / "S01" / "real" / "frame_0000.png", pairs / "S01" / "real" / "frame_0001.png",
                      pairs / "S02" / "real" / "frame_0000.png"])
    assert s["fid"] == pytest.approx(fid(sims, reals), rel=1e-9) and s["kid_std"] >= 0
    assert s["fid_nst"] == pytest.approx(fid(features([pairs / "S01" / "nst.png", pairs / "S02" / "nst.png"]), reals),
                                         rel=1e-9)
    gap = s["realism"]["sim_vs_real"]
    assert (gap["n_sim"], gap["n_real"]) == (2, 3) and gap["settings"]["kid_subset_size"] == 2
    assert any("below 2048" in w for w in gap["warnings"])
    # every problem named: broken photo, SUT error, no real/, another space, invalid vote, unanswered
    problems = "\n".join(s["problems"])
    for expected in ("S04: cannot read", "S04: SUT error on real/frame_0001.png", "S05: no real frames",
                     "S06: scene.json is from the scene space 'other'", "S03: voted not the same",
                     "S02: the SUT did not answer luggage"):
        assert expected in problems, expected
    rows = list(csv.DictReader((out / "agreement.csv").open()))
    assert list(rows[0]) == ["sample", "frame", "feature", "truth", "sim", "real", "category", "nst", "nst_category",
                             "stand_in"]
    row = next(r for r in rows if r["sample"] == "S01" and r["frame"] == "frame_0000.png" and r["feature"] == "luggage")
    assert row == {"sample": "S01", "frame": "frame_0000.png", "feature": "luggage", "truth": "YES", "sim": "YES",
                   "real": "NO", "category": "sim_only", "nst": "NO", "nst_category": "both_wrong", "stand_in": "True"}
    majority = next(r for r in rows if r["frame"] == "frame_0001.png" and r["feature"] == "driver_gender"
                    and r["sample"] == "S01")
    assert majority["real"] == "FEMALE" and majority["category"] == "sim_only"
    assert len(rows) == 4 + 4 + 3 + 3   # S01 two frames, S02 one, S04 the frame the SUT failed on
    html = (out / "report.html").read_text()
    assert "data:image/png;base64" in html and "Per feature, most disagreement first" in html
    assert "S03: voted not the same scenario" in html and "44.4%" in html
    # a rerun pays nothing twice: only the failing image is asked again (errors are never cached)
    calls = log.read_text().split()
    assert calls.count("S01/real/frame_0001.png") == 3 and "S03/sim.png" not in calls
    assert main(["agree", str(pairs), "--sut", sut, "--space", str(space_file), "--out", str(out),
                 "--no-realism"]) == 0
    again = log.read_text().split()[len(calls):]
    assert again == ["S04/real/frame_0001.png"] * 3
    assert json.loads((out / "summary.json").read_text())["agreement_rate"] == pytest.approx(4 / 9)


def test_sut_answers_are_escaped_in_the_report(setup, tmp_path):
    pairs, space_file, _, _ = setup
    program = tmp_path / "evil.py"
    program.write_text("import json,sys; json.load(sys.stdin); "
                       "print(json.dumps({'answers': {'driver_gender': '<script>alert(1)</script>'}}))")
    out = tmp_path / "evil"
    main(["agree", str(pairs), "--sut", f"command:{sys.executable} {program}", "--space", str(space_file),
          "--out", str(out), "--no-realism", "--repeats", "1"])
    html = (out / "report.html").read_text()
    assert "<script>alert" not in html and "&lt;script&gt;alert(1)&lt;/script&gt;" in html


def test_nothing_compared_exits_non_zero_but_still_reports(tmp_path, capsys):
    space_file = tmp_path / "mini.toml"
    space_file.write_text(SPACE)
    d = tmp_path / "pairs" / "S01"
    d.mkdir(parents=True)
    (d / "scene.json").write_text(json.dumps({"space": "mini", "scene": SCENES["S01"]}))
    drawing(0).save(d / "sim.png")
    program = tmp_path / "sut.py"
    program.write_text("import sys; sys.exit(3)")
    out = tmp_path / "out"
    assert main(["agree", str(tmp_path / "pairs"), "--sut", f"command:{sys.executable} {program}",
                 "--space", str(space_file), "--out", str(out), "--no-realism"]) == 1
    s = json.loads((out / "summary.json").read_text())
    assert s["n_features_compared"] == 0 and s["agreement_rate"] is None
    assert "no real frames" in (out / "report.html").read_text()
    assert "nothing could be compared" in capsys.readouterr().err


def test_categories_and_rates_follow_the_paper():
    assert category("correct", "correct") == "both_correct"
    assert category("wrong", "wrong") == "both_wrong"
    assert category("correct", "wrong") == "sim_only" and category("wrong", "correct") == "real_only"
    assert category("correct", "missing") == "unanswered" and category("invalid", "correct") == "unanswered"
    c = counts(["both_correct", "both_wrong", "sim_only", "real_only", "occluded"])
    assert c["compared"] == 4 and c["agreement_rate"] == 0.5 and c["occluded"] == 1
    assert counts([])["agreement_rate"] is None


def test_votes_majority_with_ties():
    assert verdict({}) == UNVOTED
    assert verdict({"a": True}) == VALID and verdict({"a": False}) == INVALID
    assert verdict({"a": True, "b": False}) == TIED
    assert verdict({"a": True, "b": False, "c": True}) == VALID
    assert verdict({"a": False, "b": False, "c": True}) == INVALID


def test_votes_are_asked_one_pair_at_a_time_and_saved_at_once(setup, monkeypatch, capsys):
    pairs = setup[0]
    replies = iter(["maybe", "y", "n", "q"])   # a word it does not know is asked again
    monkeypatch.setattr("builtins.input", lambda prompt="": next(replies))
    assert main(["agree", "votes", str(pairs), "--annotator", "zoe"]) == 0
    votes = {s: json.loads((pairs / s / "votes.json").read_text())["votes"] for s in ("S01", "S02")}
    assert votes["S01"]["zoe"]["same"] is True and votes["S02"]["zoe"]["same"] is False
    assert not (pairs / "S04" / "votes.json").exists()   # quit before it: nothing written
    assert (pairs / "review.html").is_file()
    assert "validity:" in capsys.readouterr().out
    assert main(["agree", "votes", str(pairs), "--annotator", "zoe", "--vote", "S01=perhaps"]) == 2


def test_sut_options_reach_the_sut_and_a_malformed_one_is_one_line(tmp_path, monkeypatch, capsys):
    import isu_validate.agree as agree_pkg
    seen = {}

    def measure(pairs, out, settings, overwrite=False):
        seen["options"] = settings.sut_options
        raise SystemExit(0)
    monkeypatch.setattr(agree_pkg, "measure_agreement", measure)
    with pytest.raises(SystemExit):
        main(["agree", str(tmp_path), "--sut", "reference", "--sut-option", "model_dir=models/retrained",
              "--out", str(tmp_path / "out")])
    assert seen["options"] == {"model_dir": "models/retrained"}
    assert main(["agree", str(tmp_path), "--sut", "reference", "--sut-option", "model_dir",
                 "--out", str(tmp_path / "out2")]) == 2
    assert "must read NAME=VALUE" in capsys.readouterr().err and not (tmp_path / "out2").exists()
