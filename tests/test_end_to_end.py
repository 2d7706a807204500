"""The whole loop for real: Blender renders, the reference ISU answers, the judge scores,
the archive commits, the report is written. Small, but nothing is a double."""
import csv
import json

import pytest

from isu_validate.cli import main
from isu_validate.space import load_space

pytestmark = [pytest.mark.blender, pytest.mark.slow]


def test_a_small_real_run_renders_asks_judges_and_reports(tmp_path, capsys):
    run_dir = tmp_path / "run"
    assert main(["run", "--sut", "reference", "--budget", "4", "--pop-size", "2", "--seed", "3",
                 "--preset", "draft", "--out", str(run_dir)]) == 0
    out = capsys.readouterr().out
    assert "4 tests (4 evaluated now)" in out and "report:" in out
    assert main(["export", str(run_dir), "--out", str(tmp_path / "tests.csv")]) == 0
    rows = list(csv.DictReader((tmp_path / "tests.csv").open()))
    assert len(rows) == 4
    weights = {f.name: f.weight for f in load_space().predicted}
    for row in rows:
        assert row["sut_error"] == "" and row["render_error"] == ""
        assert float(row["render_s"]) > 0 and float(row["sut_s"]) > 0
        assert (run_dir / row["image"]).stat().st_size > 10_000  # a real render, not a blank
        label = json.loads((run_dir / "labels" / f"{row['test_id']}.json").read_text())
        truth = label["truth"]
        assert {k[2:] for k, v in row.items() if k.startswith("y.") and v} == set(truth)  # every question answered
        # F_qa: the weighted share of the reference ISU's answers that match the label's truth (features
        # the label calls occluded are left out of it)
        scored = {k: t for k, t in truth.items() if k not in label.get("occluded", [])}
        right = sum(weights[k] for k, t in scored.items() if row[f"y.{k}"] == t)
        assert float(row["f_qa"]) == pytest.approx(right / sum(weights[k] for k in scored))
        assert row["failed"] == str(int(float(row["f_qa"]) < 1.0))
    html = (run_dir / "report.html").read_text()
    assert "<html" in html.lower() and "Failure rates at thresholds" in html and "reference" in html
