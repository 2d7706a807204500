"""Messages that tell the truth (issue 27, section 3): what resumes an interrupted agree, agree votes
without a terminal, review.html on every path, a pair's label file as a scene file, a scene error
that names the feature list once, no --out folder from a bad option, validity without a render."""
import io
import json
from contextlib import contextmanager
from pathlib import Path

import pytest

from isu_validate.cli import main
from isu_validate.protocols import RenderError
from isu_validate.space import SpaceError, load_space
from tests.pairs_kit import TRUTH, fixed_sut, make_sample, space_file


@pytest.fixture()
def pairs(tmp_path):
    root = tmp_path / "pairs"
    make_sample(root, "S01", [True], seed=1)
    make_sample(root, "S02", [False], seed=2)
    return root


def test_ctrl_c_in_agree_says_what_resumes_it(pairs, tmp_path, monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr("isu_validate.agree.measure_agreement", interrupted)
    assert main(["agree", str(pairs), "--sut", "reference", "--out", str(tmp_path / "agree")]) == 130
    err = capsys.readouterr().err
    assert "--resume" not in err and "run the same command again" in err and "cache" in err


def test_ctrl_c_in_agree_votes_says_the_votes_are_kept(pairs, monkeypatch, capsys):
    def interrupted(prompt=""):
        raise KeyboardInterrupt
    monkeypatch.setattr("builtins.input", interrupted)
    assert main(["agree", "votes", str(pairs), "--annotator", "ann"]) == 130
    err = capsys.readouterr().err
    assert "--resume" not in err and "every vote given so far is saved" in err


def test_agree_votes_without_a_terminal_is_one_line_and_keeps_the_votes(pairs, monkeypatch, capsys):
    monkeypatch.setattr("sys.stdin", io.StringIO("y\n"))   # one answer, then the end of the input
    assert main(["agree", "votes", str(pairs), "--annotator", "ann"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "EOFError" not in err
    assert err.strip().splitlines() == [
        "isu-validate agree: error: no answer to read: standard input is closed or at its end (no terminal?); "
        "the 1 vote(s) given are saved; vote in a terminal, or without one with --vote SAMPLE=yes|no"]
    assert json.loads((pairs / "S01" / "votes.json").read_text())["votes"]["ann"]["same"] is True


def test_votes_given_on_the_command_line_write_the_review_page(pairs, capsys):
    assert main(["agree", "votes", str(pairs), "--annotator", "ann", "--vote", "S01=yes"]) == 0
    review = (pairs / "review.html").read_text()
    assert "ann: same" in review and "stand-in render frame_0000.png (not a photo)" in review
    assert f"review the pairs side by side in {pairs / 'review.html'}" in capsys.readouterr().out


def test_a_bad_vote_records_none_of_the_others(pairs, capsys):
    assert main(["agree", "votes", str(pairs), "--annotator", "ann", "--vote", "S01=yes",
                 "--vote", "S02=perhaps"]) == 2
    assert not (pairs / "S01" / "votes.json").exists()


def test_validity_does_not_count_a_sample_whose_render_was_deleted(pairs, capsys):
    assert main(["agree", "votes", str(pairs), "--annotator", "ann", "--vote", "S01=yes", "--vote", "S02=yes"]) == 0
    (pairs / "S02" / "sim.png").unlink()
    capsys.readouterr()
    assert main(["agree", "votes", str(pairs), "--annotator", "bob", "--vote", "S01=yes"]) == 0
    assert "validity: 100.0% (1 valid, 0 invalid, 0 tied, 0 without votes; 1 without sim.png, not counted)" in \
        capsys.readouterr().out
    from isu_validate.agree.votes import tally
    from isu_validate.pairs import PairsDir
    validity = tally(PairsDir(pairs).samples()).to_json()
    assert validity["valid"] == 1 and validity["without_render"] == ["S02"]
    assert main(["agree", "votes", str(pairs), "--annotator", "ann", "--vote", "S02=yes"]) == 2
    assert "sim.png is missing" in capsys.readouterr().err


@pytest.mark.parametrize("bad", [["--sut", "nosuch:thing"], ["--sut", "reference", "--space", "no-such-space"],
                                 ["--sut", "reference", "--repeats", "0"]])
def test_agree_with_a_bad_option_leaves_no_out_folder(pairs, tmp_path, capsys, bad):
    out = tmp_path / "agree"
    assert main(["agree", str(pairs), *bad, "--out", str(out)]) == 2
    assert not out.exists()


def test_agree_leaves_out_a_sample_whose_render_was_deleted(pairs, tmp_path, capsys):
    (pairs / "S02" / "sim.png").unlink()
    sut = fixed_sut(tmp_path, {"S01/sim.png": TRUTH, "S01/real/frame_0000.png": TRUTH})
    out = tmp_path / "agree"
    assert main(["agree", str(pairs), "--sut", sut, "--space", str(space_file(tmp_path)), "--out", str(out),
                 "--no-realism", "--repeats", "1"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["n_samples"] == 1 and s["validity"]["without_render"] == ["S02"]


@contextmanager
def _renderer(scenes: list, *args, **kwargs):
    class Renderer:
        def render(self, scene, out: Path):
            scenes.append(scene)
            raise RenderError("no Blender here")
    yield Renderer()


def test_render_takes_a_pairs_label_file(pairs, tmp_path, monkeypatch, capsys):
    scenes = []
    monkeypatch.setattr("isu_validate.render.open_renderer", lambda *a, **k: _renderer(scenes))
    label = pairs / "S01" / "scene.json"
    assert main(["render", str(label), "--space", str(space_file(tmp_path)), "--out", str(tmp_path / "x.png")]) == 1
    assert scenes == [json.loads(label.read_text())["scene"]]   # the scene reached the renderer, checked


def test_a_scene_error_names_the_feature_list_once(tmp_path):
    space = load_space()
    with pytest.raises(SpaceError) as caught:
        space.check({"test_id": "t", "space": "isu-paper", "truth": {}, "occluded": [], "visible": {}})
    message = str(caught.value)
    assert message.count("known:") == 1 and "unknown features 'test_id', 'space', 'truth'" in message


def test_render_names_a_label_without_a_scene_object(tmp_path, capsys):
    label = tmp_path / "label.json"
    label.write_text(json.dumps({"scene": ["not", "a", "scene"]}))
    assert main(["render", str(label), "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "label file with a 'scene' object" in err
