"""``isu-validate bench recognise``: speed against realism. Per preset, render seconds per frame (the
dataset's own cost record) against the rates at which models trained on real photographs recognise what
the frames show (``isu-validate recognise``).

Renders a seeded dataset per preset into OUT/<preset> (the same scenes at every preset), or takes datasets
with ``--datasets`` (their preset read from each; an unfinished one counts the images it has)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from isu_validate.devices import add_device_argument

# the measures the table shows (all of them are in each OUT/<preset>-recognise/summary.json)
COLUMNS = ("face found", "HAPPY read happy", "SERIOUS read not happy", "phone top-5", "bottle top-5",
           "bottle top-5 upright")


def register_bench(sub) -> None:
    p = sub.add_parser("recognise", help="render seconds per frame against photo-trained models' recognition "
                                         "rates, per preset")
    p.add_argument("--presets", default="draft,standard", help="comma list (default draft,standard)")
    p.add_argument("--n", type=int, default=24, help="scenes per preset (default 24)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--datasets", nargs="+", type=Path, default=[],
                   help="finished datasets to measure instead of rendering (one per preset)")
    p.add_argument("--out", type=Path, default=Path("runs/bench-recognise"), help="folder for datasets and reports")
    add_device_argument(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from isu_validate.devices import resolve_torch_device
    from isu_validate.recognition import photos
    from isu_validate.recognition.read import Yardsticks

    device = resolve_torch_device(args.device)
    datasets = args.datasets or [_render(args, preset) for preset in _presets(args.presets)]
    rows = [_measure(folder, args.out, device) for folder in datasets]
    print(format_rows(rows))
    # the same models on real photographs: what a rate on renders is read against
    calibration = photos.calibration(Yardsticks.load(device.name))
    print(photos.format_calibration(calibration))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(json.dumps({"device": device.describe(), "rows": rows,
                                                     "real_photographs": calibration}, indent=1))
    print(f"datasets and reports in {args.out}", file=sys.stderr)
    return 0


def _presets(text: str) -> list[str]:
    from isu_validate.errors import InputError
    from isu_validate.render.presets import get_preset

    names = [p.strip() for p in text.split(",") if p.strip()]
    if not names:
        raise InputError("--presets names no preset (e.g. --presets draft,standard)")
    return [get_preset(n).name for n in names]


def _render(args, preset: str) -> Path:
    from isu_validate.dataset.build import build_dataset
    from isu_validate.dataset.settings import DatasetSettings

    folder = args.out / preset
    resume = (folder / "dataset.json").is_file()     # a rerun continues (and reuses) its own renders
    build_dataset(DatasetSettings(n=args.n, seed=args.seed, preset=preset), folder, resume=resume)
    return folder


def _measure(folder: Path, out: Path, device) -> dict:
    from isu_validate.dataset.card import costs
    from isu_validate.dataset.folder import open_dataset
    from isu_validate.yardstick.measure import RecogniseSettings, recognise

    dataset = open_dataset(folder)
    preset = dataset.info()["preset"]["name"]
    # the dataset's own per-image timings (an unfinished dataset counts the images it has); CPU-seconds too,
    # since wall seconds on a shared machine measure the neighbours as much as the preset
    cost = costs([e for e in dataset.entries().values() if e.get("status") == "ok"], 0.0, 0)
    summary = recognise(RecogniseSettings((str(folder.resolve()),)), out / f"{preset}-recognise", device)
    rates = {r["measure"]: r for r in summary["rows"] if r["split"] == "all" and r["kind"] == "render"}
    return {"preset": preset, "dataset": str(folder), "frames": summary["frames"]["render"],
            "render_s_per_frame": cost["render_s_per_image"], "render_cpu_s_per_frame": cost["cpu_s_per_image"],
            "recognise_s_per_frame": summary["timing"]["per_frame_s"],
            "recognise_cpu_s_per_frame": summary["timing"]["cpu_s_per_frame"],
            "rates": {m: {k: rates[m][k] for k in ("rate", "hits", "n", "ci95")} for m in COLUMNS if m in rates}}


def format_rows(rows: list[dict]) -> str:
    head = (f"{'preset':<10}{'render s/frame':>15}{'CPU-s/frame':>12}{'frames':>8}"
            + "".join(f"{c:>24}" for c in COLUMNS))
    lines = [head]
    for row in rows:
        s, cpu = (f"{v:.2f}" if v is not None else "-"
                  for v in (row["render_s_per_frame"], row["render_cpu_s_per_frame"]))
        cells = "".join(f"{_rate(row['rates'].get(c)):>24}" for c in COLUMNS)
        lines.append(f"{row['preset']:<10}{s:>15}{cpu:>12}{row['frames']:>8}{cells}")
    return "\n".join(lines)


def _rate(r: dict | None) -> str:
    if not r or not r["n"]:
        return "-"
    return f"{r['rate']:.0%} [{r['ci95'][0]:.0%}-{r['ci95'][1]:.0%}] n{r['n']}"
