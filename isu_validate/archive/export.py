"""The tests table of a run as CSV (a contract, docs/ARCHITECTURE.md), one row per evaluated test.

Beyond the contract: ``visible.<feature>`` is the visible share of each feature that names render
parts (empty where the scene has nothing of it to see), and ``occluded`` lists the features the frame
showed too little of to be judged (left out of the fitness), separated by ``;``."""
from __future__ import annotations

import csv
from pathlib import Path
from typing import IO

from .run_dir import ARCHIVE_FILE, RunDir, RunDirError
from .store import TestRecord

BASE_COLUMNS = ["test_id", "algorithm", "seed", "generation"]
TAIL_COLUMNS = ["f_div", "failed", "occluded", "sut_error", "render_error", "render_s", "sut_s", "image"]


def _feature_names(run_dir: RunDir) -> tuple[list[str], list[str], list[str]]:
    """All features, the predicted ones (the SUT's answers exist only for those), and those with a
    visibility (predicted features that name the render parts showing them)."""
    features = run_dir.info()["space"]["features"]
    predicted = [n for n, f in features.items() if f.get("predicted")]
    return list(features), predicted, [n for n in predicted if features[n].get("visible_parts")]


def rows(run_dir: Path) -> tuple[list[str], list[dict]]:
    run_dir = RunDir(Path(run_dir))
    if not run_dir.has_archive():
        raise RunDirError(f"{run_dir.path} is not a run directory (no {ARCHIVE_FILE}); "
                          "give the folder `run --out` wrote")
    features, predicted, seen = _feature_names(run_dir)
    records = run_dir.records()
    fitness_keys = sorted({k for r in records for k in r.fitness})
    columns = (BASE_COLUMNS + [f"x.{f}" for f in features] + [f"y.{f}" for f in predicted]
               + [f"visible.{f}" for f in seen] + fitness_keys + TAIL_COLUMNS)
    return columns, [_row(r, features, predicted, seen, fitness_keys) for r in records]


def _row(record: TestRecord, features: list[str], predicted: list[str], seen: list[str],
         fitness_keys: list[str]) -> dict:
    row = {"test_id": record.test_id, "algorithm": record.algorithm, "seed": record.seed,
           "generation": record.generation}
    answers = record.answers or {}
    for f in features:
        row[f"x.{f}"] = record.canonical.get(f, "")
    for f in predicted:
        row[f"y.{f}"] = answers.get(f, "")
    visibility = record.visibility
    for f in seen:
        row[f"visible.{f}"] = visibility.get(f, "")
    for k in fitness_keys:
        row[k] = record.fitness.get(k, "")
    row.update(f_div=round(record.f_div, 6), failed=int(record.failed), occluded=";".join(record.occluded),
               sut_error=record.sut_error or "",
               render_error=record.render_error or "", render_s=record.render_s or "", sut_s=record.sut_s or "",
               image=record.image or "")
    return row


def write_csv(run_dir: Path, out: IO[str]) -> int:
    columns, data = rows(run_dir)
    writer = csv.DictWriter(out, fieldnames=columns)
    writer.writeheader()
    writer.writerows(data)
    return len(data)


def tests_table(run_dir: str | Path):
    """A run's tests as a pandas DataFrame: exactly what ``isu-validate export`` writes, read back
    (empty cells are missing values; answers such as ``NONE`` or ``NA`` stay text).

        tests = tests_table("runs/surrogate-s1")
        tests[tests.failed == 1][["test_id", "f_qa", "occluded"]]
    """
    import io

    import pandas as pd

    text = io.StringIO()
    write_csv(Path(run_dir), text)
    text.seek(0)
    return pd.read_csv(text, keep_default_na=False, na_values=[""])
