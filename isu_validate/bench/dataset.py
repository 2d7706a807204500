"""``isu-validate bench dataset``: how fast ``dataset`` makes images with masks, against how exactly its COCO
masks hold what the renderer's seg channel shows.

For each ``--workers`` value it builds a fresh uniform dataset of ``--n`` scenes (``build_dataset``, as the
command does) and reads its speed from the build itself: renders per second over the whole build (Blender's
start included) and in steady state (between the first and the last image committed, from the manifest's
file times). Then ``--check`` of its images are rendered again with the seg channel and their decoded RLE
masks compared with the ids pixel by pixel: the share of frames whose masks all agree, and of pixels that
differ. The goal of the issue: >= 1.6 images/s at draft with masks on the 2-core machine. CPU seconds per
image (Blender's worker and the host process) give the rate the machine's cores allow when idle.
"""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path


def register_bench(sub) -> None:
    p = sub.add_parser("dataset", help="dataset: images/s with masks, and COCO masks against a re-render")
    p.add_argument("--n", type=int, default=40, help="scenes per build (default 40)")
    p.add_argument("--workers", default="1,2", help="comma list of local worker counts (default 1,2)")
    p.add_argument("--preset", default="draft", help="render preset (default draft)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--check", type=int, default=3, help="images re-rendered to check their masks (default 3)")
    p.add_argument("--out", type=Path, default=Path("runs/bench-dataset"),
                   help="folder for the builds (each replaced by the next run of the bench)")
    p.add_argument("--json", type=Path, help="also write the rows here")
    p.set_defaults(func=run)


def run(args) -> int:
    from isu_validate.dataset import DatasetSettings, build_dataset

    rows = []
    for workers in [int(w) for w in args.workers.split(",") if w.strip()]:
        out = args.out / f"workers-{workers}"
        shutil.rmtree(out, ignore_errors=True)
        settings = DatasetSettings(n=args.n, seed=args.seed, preset=args.preset, workers=workers)
        summary = build_dataset(settings, out, log=lambda text: None)
        row = {"workers": workers, "renders": summary.renders, "seconds": round(summary.seconds, 1),
               "renders_per_s": round(summary.renders_per_s, 3), "steady_renders_per_s": _steady_rate(out),
               **_cpu(out), **_mask_check(out, args.preset, args.check)}
        rows.append(row)
        _print(row)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


def _steady_rate(out: Path) -> float | None:
    """Images per second between the first and the last manifest entry committed (no start-up in it)."""
    times = sorted(p.stat().st_mtime for p in (out / "manifest").glob("*.json"))
    return round((len(times) - 1) / (times[-1] - times[0]), 3) if len(times) > 2 and times[-1] > times[0] else None


def _cpu(out: Path) -> dict:
    """CPU seconds per image (Blender's worker and the host process, median over the build), and the images/s
    they would allow on this machine's cores with nothing else running: a bound that load does not move much,
    where the wall-clock rates above depend on what else the machine does."""
    import os
    import statistics

    timings = [json.loads(p.read_text()).get("timings", {}) for p in (out / "manifest").glob("*.json")]
    spent = [t["worker_cpu_s"] + t["host_cpu_s"] for t in timings if t.get("worker_cpu_s") is not None]
    if not spent:
        return {"cpu_s_per_image": None, "idle_bound_per_s": None}
    cpu = statistics.median(spent)
    return {"cpu_s_per_image": round(cpu, 3), "idle_bound_per_s": round((os.cpu_count() or 1) / cpu, 2)}


def _mask_check(out: Path, preset: str, k: int) -> dict:
    import cv2
    import numpy as np
    from pycocotools import mask as rle_codec

    from isu_validate.dataset import open_dataset
    from isu_validate.render import open_renderer

    entries = [e for e in open_dataset(out).entries().values() if e["status"] == "ok"][:k]
    agree, differing, pixels = 0, 0, 0
    with open_renderer(preset, channels=("seg",), log_dir=out / "logs") as renderer:
        for entry in entries:
            frame = renderer.render(entry["scene"], out / ".check" / f"{entry['slot']:06d}.png")
            ids = cv2.imread(str(frame.channels["seg"]), cv2.IMREAD_UNCHANGED)
            decoded = np.zeros_like(ids)
            for ann in entry["annotations"]:
                rle = {"size": ann["segmentation"]["size"], "counts": ann["segmentation"]["counts"].encode()}
                decoded[rle_codec.decode(rle).astype(bool)] = ann["category_id"]
            known = np.isin(ids, [a["category_id"] for a in entry["annotations"]]) | (ids == 0)
            wrong = int(((decoded != ids) & known).sum() + (~known).sum())
            agree += wrong == 0
            differing += wrong
            pixels += ids.size
    shutil.rmtree(out / ".check", ignore_errors=True)
    return {"frames_checked": len(entries), "frames_masks_agree": agree,
            "pixels_differing": round(differing / pixels, 6) if pixels else None}


def _print(row: dict) -> None:
    steady = row["steady_renders_per_s"]
    print(f"workers {row['workers']}: {row['renders']} renders in {row['seconds']} s = {row['renders_per_s']:.2f} "
          f"renders/s ({steady if steady is not None else '-'} /s steady; {row['cpu_s_per_image']} CPU-s per image: "
          f"<= {row['idle_bound_per_s']} /s on these cores idle); masks agree with a re-render in "
          f"{row['frames_masks_agree']} of {row['frames_checked']} frames, "
          f"{row['pixels_differing']} of pixels differ", file=sys.stdout)
