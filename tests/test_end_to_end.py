"""The whole loop for real: Blender renders, the reference ISU answers, the judge scores,
the archive commits, the report is written. Small, but nothing is a double."""
import csv
import json

import pytest

from isu_validate.cli import main

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
    for row in rows:
        assert row["sut_error"] == "" and row["render_error"] == ""
        assert 0.0 <= float(row["f_qa"]) <= 1.0
        assert float(row["render_s"]) > 0 and float(row["sut_s"]) > 0
        assert (run_dir / row["image"]).stat().st_size > 10_000  # a real render, not a blank
        label = json.loads((run_dir / "labels" / f"{row['test_id']}.json").read_text())
        asked = {k for k in label["truth"]}
        assert {k[2:] for k, v in row.items() if k.startswith("y.") and v} <= asked
    html = (run_dir / "report.html").read_text()
    assert "<html" in html.lower() and "Failure rates at thresholds" in html and "reference" in html
