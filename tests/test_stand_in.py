"""A stand-in never passes for reality (issue 27, section 1): wherever captured frames are taken for
real (agree, exposure check, realism on pairs, stylize --pairs), the stand-in renders among them are
counted, flagged first, and a mixed folder gives its figures on each kind apart."""
import csv
import json

import pytest

from isu_validate.cli import main
from tests.pairs_kit import TRUTH, WRONG, fixed_sut, make_sample, space_file

pytestmark = pytest.mark.usefixtures("few_torch_threads")


def test_the_sidecar_says_which_frames_are_stand_ins(tmp_path):
    from capture.sidecar import banner, provenance
    pairs = tmp_path / "pairs"
    frames = sorted((make_sample(pairs, "S01", [True, False, True]) / "real").glob("*.png"))
    (frames[2].with_suffix(".json")).write_text("not json")   # unreadable: not known to be a stand-in
    marks = provenance(frames)
    assert marks.stand_in == (frames[0],) and marks.real == (frames[1], frames[2])
    assert marks.counts() == {"stand_in_frames": 1, "real_frames": 2}
    assert banner(0, 5) == ""
    assert "all 2 'real' frame(s) are stand-ins" in banner(2, 0) and "1 of 3 'real' frames" in banner(1, 2)


def test_agree_on_stand_ins_says_so_in_every_output(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [True, True])
    sut = fixed_sut(tmp_path, {"S01/sim.png": TRUTH, "S01/real/frame_0000.png": TRUTH,
                               "S01/real/frame_0001.png": TRUTH})
    out = tmp_path / "agree"
    assert main(["agree", str(pairs), "--sut", sut, "--space", str(space_file(tmp_path)), "--out", str(out),
                 "--no-realism", "--repeats", "1"]) == 0
    console = capsys.readouterr().out.splitlines()
    assert console[0].startswith("STAND-IN FRAMES: all 2 'real' frame(s) are stand-ins")
    assert "2 'real' frames, 2 of them stand-in renders" in console[1]
    s = json.loads((out / "summary.json").read_text())
    assert (s["stand_in_frames"], s["real_frames"]) == (2, 0) and s["agreement_rate"] == 1.0
    rows = list(csv.DictReader((out / "agreement.csv").open()))
    assert len(rows) == 6 and {r["stand_in"] for r in rows} == {"True"}
    html = (out / "report.html").read_text()
    main_part = html[html.index("<main>"):]
    assert main_part.index("STAND-IN FRAMES") < main_part.index("Summary")   # the banner comes first
    assert "not a real-world result" in html


def test_agree_on_a_mixed_folder_gives_the_agreement_on_each_kind_apart(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [True, False])    # the stand-in agrees with the render, the photo does not
    sut = fixed_sut(tmp_path, {"S01/sim.png": TRUTH, "S01/real/frame_0000.png": TRUTH,
                               "S01/real/frame_0001.png": WRONG})
    out = tmp_path / "agree"
    assert main(["agree", str(pairs), "--sut", sut, "--space", str(space_file(tmp_path)), "--out", str(out),
                 "--no-realism", "--repeats", "1"]) == 0
    console = capsys.readouterr().out
    assert console.startswith("STAND-IN FRAMES: 1 of 2 'real' frames are stand-ins")
    assert "apart: on real captures 0.0% of 3 features (1 frames); on stand-ins 100.0% of 3 features" in console
    s = json.loads((out / "summary.json").read_text())
    assert (s["stand_in_frames"], s["real_frames"], s["agreement_rate"]) == (1, 1, 0.5)
    by = s["by_provenance"]
    assert (by["real"]["agreement_rate"], by["real"]["frames"], by["real"]["sim_only"]) == (0.0, 1, 3)
    assert (by["stand_in"]["agreement_rate"], by["stand_in"]["frames"]) == (1.0, 1)
    rows = list(csv.DictReader((out / "agreement.csv").open()))
    assert {(r["frame"], r["stand_in"]) for r in rows} == {("frame_0000.png", "True"), ("frame_0001.png", "False")}
    html = (out / "report.html").read_text()
    assert "agreement on real captures (1 frames, 3 features)" in html and "0.0%" in html


def test_agree_on_real_captures_alone_shows_no_banner(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [False])
    sut = fixed_sut(tmp_path, {"S01/sim.png": TRUTH, "S01/real/frame_0000.png": TRUTH})
    out = tmp_path / "agree"
    assert main(["agree", str(pairs), "--sut", sut, "--space", str(space_file(tmp_path)), "--out", str(out),
                 "--no-realism", "--repeats", "1"]) == 0
    assert "STAND-IN" not in capsys.readouterr().out and "STAND-IN" not in (out / "report.html").read_text()
    assert json.loads((out / "summary.json").read_text())["real_frames"] == 1


def test_exposure_check_counts_stand_ins_and_keeps_a_mixed_set_apart(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [True, False], seed=1)
    make_sample(pairs, "S02", [False], seed=2)
    out = tmp_path / "chk"
    assert main(["exposure", "check", str(pairs), "--out", str(out)]) == 0
    console = capsys.readouterr().out
    assert console.startswith("STAND-IN FRAMES: 1 of 3 'real' frames are stand-ins")
    assert "real (2 pairs): mean |luma difference|" in console and "stand-in (1 pairs)" in console
    check = json.loads((out / "check.json").read_text())
    s = check["summary"]
    assert (s["stand_in_frames"], s["real_frames"], s["pairs"]) == (1, 2, 3)
    assert s["by_provenance"]["real"]["pairs"] == 2 and s["by_provenance"]["stand_in"]["pairs"] == 1
    assert [r["stand_in"] for r in check["pairs"]] == [True, False, False]
    html = (out / "report.html").read_text()
    assert html.index("STAND-IN FRAMES") < html.index("Renders against captures")


def test_exposure_check_of_two_folders_reads_the_captures_sidecars(tmp_path, capsys):
    sample = make_sample(tmp_path / "pairs", "S01", [True])
    (tmp_path / "sim").mkdir()
    (tmp_path / "sim" / "frame_0000.png").write_bytes((sample / "sim.png").read_bytes())
    assert main(["exposure", "check", str(tmp_path / "sim"), str(sample / "real"), "--out", str(tmp_path / "chk"),
                 "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert (s["stand_in_frames"], s["real_frames"]) == (1, 0)


def test_realism_on_pairs_counts_stand_ins_and_compares_each_kind_apart(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [True, False], seed=1)
    make_sample(pairs, "S02", [True, False], seed=2)
    report = tmp_path / "realism.json"
    assert main(["realism", "--pairs", str(pairs), "--bootstrap", "0", "--kid-subsets", "5", "--out", str(report),
                 "--cache-dir", str(tmp_path / "cache"), "--threads", "2"]) == 0
    console = capsys.readouterr().out
    assert console.startswith(f"{pairs}:real: STAND-IN FRAMES: 2 of 4 'real' frames are stand-ins")
    name = f"{pairs}:sim vs {pairs}:real"
    result = json.loads(report.read_text())
    assert set(result) == {name, f"{name} (real captures only)", f"{name} (stand-ins only)"}
    assert (result[name]["stand_in_frames"], result[name]["real_frames"], result[name]["n_b"]) == (2, 2, 4)
    real_only = result[f"{name} (real captures only)"]
    assert (real_only["stand_in_frames"], real_only["real_frames"], real_only["n_b"]) == (0, 2, 2)
    assert result[f"{name} (stand-ins only)"]["stand_in_frames"] == 2


def test_stylize_pairs_says_when_its_style_photo_is_a_stand_in(tmp_path, capsys):
    pairs = tmp_path / "pairs"
    make_sample(pairs, "S01", [True], seed=1)
    style = pairs / "S01" / "real" / "frame_0000.png"
    assert main(["stylize", "--style", str(style), "--pairs", str(pairs), "--method", "gatys", "--size", "32",
                 "--steps", "1", "--threads", "2"]) == 0
    assert "STAND-IN FRAMES: all 1 'real' frame(s) are stand-ins" in capsys.readouterr().err
    report = json.loads((pairs / "nst.json").read_text())
    assert (report["stand_in_frames"], report["real_frames"]) == (1, 0)
