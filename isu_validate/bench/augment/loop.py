"""The loop end to end, stage by stage: find failures, make data, retrain, replay an independent run."""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Callable

from ...errors import InputError
from .stages import Stages
from .table import GOAL_AT, THRESHOLDS, goal, table_rows
from .unfixable import not_fixed, without, wrong_counts

ROWS = ("none", "uniform", "focused", "focused-style")
# the training data of each retrained row: (dataset, variants of its images; None = all)
DATA = {"uniform": [("uniform", ("render",))], "focused": [("focused", ("render",))],
        "focused-style": [("focused", None)]}


@dataclass(frozen=True)
class AugmentSettings:
    out: Path
    n: int = 120                 # images per dataset
    budget: int = 150            # tests per random-search run
    seed: int = 0                # the finding run and the datasets; the replayed run takes seed + 1
    preset: str = "draft"
    pop_size: int = 15
    threshold: float = 0.9       # the runs' oracle: what "failing" means for the focus and McNemar
    style: str | None = None     # style image for the style row; None: a stand-in frame the bench renders
    style_steps: int = 150       # fast style net training steps (~5 s each on 2 busy cores)
    rows: tuple[str, ...] = ROWS

    def check(self) -> None:
        unknown = [r for r in self.rows if r not in ROWS]
        if unknown or "none" not in self.rows:
            raise InputError(f"--rows takes none (always) and any of {', '.join(ROWS[1:])}; got {','.join(self.rows)}")
        if self.n < 1 or self.budget < 1:
            raise InputError("--n and --budget must be at least 1")
        if self.style is not None and not Path(self.style).is_file():
            raise InputError(f"--style {self.style}: no such image")

    def identity(self) -> dict:
        """What the stages' results depend on (the rows may grow between runs)."""
        return {"n": self.n, "budget": self.budget, "seed": self.seed, "preset": self.preset,
                "pop_size": self.pop_size, "threshold": self.threshold,
                "style": str(Path(self.style).resolve()) if self.style else None, "style_steps": self.style_steps}


def run_augment(settings: AugmentSettings, steps, log: Callable[[str], None]) -> dict:
    settings.check()
    out, rows = Path(settings.out), [r for r in ROWS if r in settings.rows]
    stages = Stages(out, settings.identity(), log)
    search = stages.run("search", lambda: steps.search(out / "search", settings.seed, settings.budget))
    stages.run("replay-run", lambda: steps.search(out / "replay-run", settings.seed + 1, settings.budget))
    style, style_cost = _style(settings, steps, stages, rows)
    datasets = _datasets(settings, steps, stages, rows, style)
    models = {}
    for row in rows[1:]:
        parts = [(Path(datasets[name]["dataset"]), variants) for name, variants in DATA[row]]
        models[row] = stages.run(f"model-{row}", partial(steps.retrain, parts, out / "models" / row))
    replays = {}
    for row in rows:
        model = Path(models[row]["model"]) if row in models else None
        replays[row] = stages.run(f"replay-{row}", partial(steps.replay, out / "replay-run", out / "replays" / row,
                                                           model))
    costs = _costs(settings, rows, search, datasets, models, style_cost)
    return figures(replays, models, costs, steps.verdicts(out / "replay-run"), search)


def _style(settings, steps, stages: Stages, rows) -> tuple[tuple[str, str] | None, float]:
    """(style image, fast net) for the style row, and the minutes they took."""
    if "focused-style" not in rows:
        return None, 0.0
    minutes = 0.0
    image = settings.style
    if image is None:
        frame = stages.run("style-image", lambda: steps.stand_in_frame(Path(settings.out) / "style", settings.seed))
        image, minutes = frame["image"], frame["minutes"]
    net = stages.run("style-model", lambda: steps.train_style(image, Path(settings.out) / "search",
                                                              Path(settings.out) / "style" / "fast.pt",
                                                              settings.style_steps))
    return (str(image), net["model"]), minutes + net["minutes"]


def _datasets(settings, steps, stages: Stages, rows, style) -> dict:
    out, made = Path(settings.out) / "datasets", {}
    if "uniform" in rows:
        made["uniform"] = stages.run("dataset-uniform", lambda: steps.dataset(
            out / "uniform", settings.n, settings.seed, None, None))
    if "focused" in rows or "focused-style" in rows:
        name = "focused-styled" if style else "focused"   # one dataset serves both focused rows
        made["focused"] = stages.run(f"dataset-{name}", lambda: steps.dataset(
            out / name, settings.n, settings.seed, Path(settings.out) / "search", style))
    return made


def _costs(settings, rows, search: dict, datasets: dict, models: dict, style_minutes: float) -> dict:
    """What each row's data cost: renders (the focused rows count the finding run's too) and minutes
    (finding run, dataset, style, retrain)."""
    costs = {"none": {}}
    for row in rows[1:]:
        data = datasets["uniform" if row == "uniform" else "focused"]
        focused = row != "uniform"
        costs[row] = {"renders": data["renders"] + (search["renders"] if focused else 0),
                      "styled": data["images"] - data["renders"] if row == "focused-style" else 0,
                      "minutes": data["minutes"] + models[row]["minutes"] + (search["minutes"] if focused else 0)
                      + (style_minutes if row == "focused-style" else 0)}
    return costs


def figures(replays: dict, models: dict, costs: dict, verdicts: dict, search: dict) -> dict:
    """The table's rows and goal; then the features retraining did not fix and the same without them."""
    rates = {row: {t: _rate(r, t) for t in THRESHOLDS} for row, r in replays.items()}
    rows = table_rows(rates, {row: r["mcnemar"]["p"] for row, r in replays.items()}, models, costs)
    result = {"rows": rows, "goal": goal(rows), "search": {k: search[k] for k in ("tests", "failures", "renders")},
              "errors": {row: wrong_counts(r["per_feature"]) for row, r in replays.items()}}
    if "focused" in replays:
        left_out = not_fixed(result["errors"]["none"], result["errors"]["focused"])
        result["not_fixed"] = left_out
        if left_out:
            rest = {row: without(verdicts, r, set(left_out), THRESHOLDS, GOAL_AT) for row, r in replays.items()}
            result["rows_without"] = table_rows({row: r["rates"] for row, r in rest.items()},
                                                {row: r["p"] for row, r in rest.items()}, models, costs)
            result["goal_without"] = goal(result["rows_without"])
    return result


def _rate(replay: dict, threshold: float) -> float | None:
    return next((r["rate_after"] for r in replay["rates"] if abs(r["threshold"] - threshold) < 1e-9), None)
