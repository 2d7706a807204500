"""``bench augment``'s stages, resume, table and goal, with doubles for the pipeline steps (no render)."""
import json

import pytest

from isu_validate.bench.augment import report
from isu_validate.bench.augment.loop import AugmentSettings, run_augment
from isu_validate.bench.augment.table import format_table
from isu_validate.bench.augment.unfixable import f_qa_without, statuses_after

def _verdicts(n: int = 20) -> dict:
    """The replayed run: test i has the emotion wrong (weight 0.05) when i < 8 and the belt (0.2) when i < 6:
    F_qa 0.75 (fails at 0.8), 0.95 (fails only at 1.0) or 1."""
    return {f"t{i:02d}": {"driver_emotion": ["wrong" if i < 8 else "correct", 0.05],
                          "seat_belt": ["wrong" if i < 6 else "correct", 0.2], "luggage": ["correct", 0.75]}
            for i in range(n)}


# per model: the tests whose belt the model gets right again (emotion is never fixed)
BELT_FIXED = {"none": 0, "uniform": 2, "focused": 5, "focused-style": 6}


class Steps:
    def __init__(self):
        self.calls = []

    def search(self, run_dir, seed, budget):
        self.calls.append(("search", run_dir.name, seed))
        return {"run": str(run_dir), "tests": budget, "failures": 7, "renders": budget}

    def verdicts(self, run_dir):
        return _verdicts()

    def stand_in_frame(self, out, seed):
        self.calls.append(("stand_in_frame",))
        return {"image": str(out / "standin.png"), "renders": 1}

    def train_style(self, style, content_run, out, steps):
        self.calls.append(("train_style", str(style)))
        return {"model": str(out)}

    def dataset(self, out, n, seed, focus_run, style):
        self.calls.append(("dataset", out.name, focus_run is not None, style is not None))
        return {"dataset": str(out), "renders": n, "images": 2 * n if style else n, "short": 0}

    def retrain(self, parts, out):
        self.calls.append(("retrain", out.name, [(p.name, v) for p, v in parts]))
        worst = -0.03 if out.name == "uniform" else -0.01
        return {"model": str(out), "change": {"worst": worst, "worst_feature": "seat_belt", "mean": 0.004},
                "comparison": {}, "extra_images": 10, "embed_seconds": 1, "fit_seconds": 1}

    def replay(self, run_dir, out, model_dir):
        row = out.name
        self.calls.append(("replay", row, model_dir.name if model_dir else None))
        fixed = BELT_FIXED[row]
        tests = []
        for test_id, statuses in _verdicts().items():
            i = int(test_id[1:])
            right = "seat_belt" if i < fixed else ""
            after = statuses_after(statuses, {"became_right": right})
            tests.append({"test_id": test_id, "f_qa_after": f_qa_without(after, set()), "became_right": right,
                          "became_wrong": ""})
        values = [t["f_qa_after"] for t in tests]
        rates = [{"threshold": t, "rate_after": sum(v < t for v in values) / len(values)} for t in (1.0, 0.9, 0.8)]
        per_feature = {"driver_emotion": {"judged": 20, "right_after": 12},
                       "seat_belt": {"judged": 20, "right_after": 14 + fixed}}
        return {"rates": rates, "mcnemar": {"p": 0.5 / (1 + fixed)}, "per_feature": per_feature,
                "n_replayed": 20, "sut_errors": 0, "tests": tests}


def test_the_loop_runs_every_stage_once_and_resumes_without_running_them_again(tmp_path):
    steps = Steps()
    settings = AugmentSettings(tmp_path / "b", n=12, budget=20)
    result = run_augment(settings, steps, log=lambda text: None)
    kinds = [c[0] for c in steps.calls]
    assert kinds.count("search") == 2 and ("search", "replay-run", 1) in steps.calls   # independent seed
    assert ("dataset", "uniform", False, False) in steps.calls
    assert ("dataset", "focused-styled", True, True) in steps.calls                    # one dataset, both rows
    assert ("retrain", "focused", [("focused-styled", ("render",))]) in steps.calls
    assert ("retrain", "focused-style", [("focused-styled", None)]) in steps.calls
    assert ("replay", "none", None) in steps.calls and ("replay", "focused", "focused") in steps.calls
    assert "stand_in_frame" in kinds                                                   # no --style given

    again = Steps()
    assert run_augment(settings, again, log=lambda text: None) == result
    assert again.calls == []
    stored = json.loads((tmp_path / "b" / "stages.json").read_text())["stages"]
    assert list(stored) == ["search", "replay-run", "style-image", "style-model", "dataset-uniform",
                            "dataset-focused-styled", "model-uniform", "model-focused", "model-focused-style",
                            "replay-none", "replay-uniform", "replay-focused", "replay-focused-style"]

    with pytest.raises(ValueError, match="other settings.*n: 12 stored, 24 now"):
        run_augment(AugmentSettings(tmp_path / "b", n=24, budget=20), Steps(), log=lambda text: None)


def test_the_table_cuts_against_none_and_judges_the_goal(tmp_path):
    result = run_augment(AugmentSettings(tmp_path / "b", n=12, budget=20), Steps(), log=lambda text: None)
    rows = {r["row"]: r for r in result["rows"]}
    # at 0.9 a test fails when its belt is wrong: 6 of 20 under the shipped model, 1 under the focused one
    assert rows["none"]["rates"][0.9] == pytest.approx(0.30)
    assert rows["focused"]["rates"][0.9] == pytest.approx(0.05) and rows["focused"]["cuts"][0.9] == pytest.approx(5 / 6)
    assert rows["uniform"]["cuts"][0.9] == pytest.approx(2 / 6)
    assert result["goal"]["verdict"] == "met"
    # the emotion stays wrong 8 times under every model: named, and the rates shown without it
    assert result["not_fixed"] == ["driver_emotion"]
    without = {r["row"]: r for r in result["rows_without"]}
    assert rows["none"]["rates"][1.0] == pytest.approx(0.40) and without["none"]["rates"][1.0] == pytest.approx(0.30)
    assert without["focused"]["rates"][1.0] == pytest.approx(0.05)
    text = report(result, AugmentSettings(tmp_path, n=12, budget=20))
    assert ("| focused 12 | 5.0% (-83%) | 5.0% (-83%) | 40.0% (+0%) | 0.0833 | -1.0 pt (seat_belt) | +0.40 pt | 32 | "
            "0.0 |") in text
    assert "goal met" in text and "not fixed by the focused retrain: driver_emotion" in text
    assert "| none (shipped) | 30.0% | 30.0% | 40.0% | - | - | - | - | - |" in text


def test_a_goal_missed_says_which_check_failed():
    rows = [{"row": "none", "rates": {0.8: 0.2, 0.9: 0.2, 1.0: 0.4}, "cuts": {0.8: None, 0.9: None, 1.0: None},
             "p": None, "worst": None, "worst_feature": None, "mean": None},
            {"row": "uniform", "rates": {0.8: 0.14, 0.9: 0.14, 1.0: 0.4}, "cuts": {0.8: 0.3, 0.9: 0.3, 1.0: 0.0},
             "p": 0.2, "worst": -0.01, "worst_feature": "child", "mean": 0.0, "renders": 12, "minutes": 3.0},
            {"row": "focused", "rates": {0.8: 0.1, 0.9: 0.1, 1.0: 0.3}, "cuts": {0.8: 0.5, 0.9: 0.5, 1.0: 0.25},
             "p": 0.01, "worst": -0.03, "worst_feature": "child", "mean": 0.01, "renders": 32, "minutes": 9.0}]
    from isu_validate.bench.augment.table import format_goal, goal

    text = format_goal(goal(rows))
    assert text.startswith("goal not met") and "NO: focused cut >= 2x the uniform cut" in text
    assert "NO: no held-out accuracy falls more than 2 points" in text
    assert "| uniform 12 | 14.0% (-30%) | 14.0% (-30%) | 40.0% (+0%) | 0.2 | -1.0 pt (child) | +0.00 pt | 12 | 3.0 |" \
        in format_table(rows, 12)


def test_rows_and_settings_are_checked(tmp_path):
    with pytest.raises(ValueError, match="--rows"):
        run_augment(AugmentSettings(tmp_path, rows=("uniform",)), Steps(), log=print)
    with pytest.raises(ValueError, match="no such image"):
        run_augment(AugmentSettings(tmp_path, style=str(tmp_path / "missing.png")), Steps(), log=print)


def test_without_the_style_row_no_style_is_made(tmp_path):
    steps = Steps()
    run_augment(AugmentSettings(tmp_path / "b", n=12, budget=20, rows=("none", "focused")), steps, log=print)
    assert ("dataset", "focused", True, False) in steps.calls
    assert not any(c[0] in ("stand_in_frame", "train_style") for c in steps.calls)
