"""``isu-validate bench render``: seconds per frame against error, per preset.

Renders a fixed set of seeded scenes with each preset (after one untimed warm-up frame, which pays
Blender's kernel load and first BVH build), and compares every frame with a converged reference render
of the same scene (PSNR, SSIM; frames of reduced-resolution presets are upscaled bicubically first)."""
from __future__ import annotations

import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from isu_validate.devices import add_render_device_argument

if TYPE_CHECKING:   # numpy and OpenCV load when the bench runs, not for its --help
    import numpy as np


def register_bench(sub) -> None:
    p = sub.add_parser("render", help="render presets: seconds per frame against PSNR/SSIM to a reference")
    p.add_argument("--presets", default="draft,standard,final", help="comma list (default draft,standard,final)")
    p.add_argument("--scenes", type=int, default=3, help="number of seeded random scenes (default 3)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--repeat", type=int, default=2, help="timed renders of each scene per preset (default 2)")
    p.add_argument("--reference-samples", type=int, default=64,
                   help="samples of the denoised reference (default 64; FACTS: 16 spp + OIDN is 43.7 dB "
                        "from a 1024-sample reference already)")
    p.add_argument("--rig", default="default")
    p.add_argument("--threads", type=int, default=0, help="Cycles threads (0 = all cores)")
    add_render_device_argument(p)   # the presets' device; the reference renders on the CPU, so PSNR/SSIM
                                    # against it measure what a GPU changes in the pixels
    p.add_argument("--sut", help="also ask this SUT (spec as in `run --sut`) about every frame and report the "
                   "share of answers unchanged against the reference frame: the error that matters")
    p.add_argument("--out", type=Path, default=Path("runs/bench-render"), help="folder for frames and bench.json; "
                   "reference renders found there are reused")
    p.add_argument("--without-people", action="store_true",
                   help="also time each preset with the driver and child left out: what the people cost")
    p.set_defaults(func=run)


def run(args) -> int:
    import numpy as np

    from isu_validate.space import load_space
    from isu_validate.render import get_preset

    space = load_space()
    scenes = space.sample(np.random.default_rng(args.seed), args.scenes)
    args.out.mkdir(parents=True, exist_ok=True)
    reference = replace(get_preset("reference"), samples=args.reference_samples, threads=args.threads)
    refs, ref_paths = _references(scenes, reference, args, space)
    sut = _SUTCheck(args.sut, space, scenes, ref_paths) if args.sut else None
    rows = []
    for name in [p.strip() for p in args.presets.split(",") if p.strip()]:
        preset = get_preset(name, threads=args.threads)
        rows.append(_bench_preset(preset, scenes, refs, args, space))
        if args.without_people:
            rows[-1]["without_people"] = _bench_preset(preset, scenes, None, args, space, people=False)
        if sut:
            rows[-1]["sut_unchanged"] = sut.unchanged([args.out / f"{preset.name}-{i}.png" for i in range(len(scenes))])
        _print_row(rows[-1])
    report = {"rig": args.rig, "render_device_asked": args.render_device, "scenes": args.scenes, "seed": args.seed,
              "repeat": args.repeat,
              "reference": {"samples": reference.samples, "denoise": reference.denoise,
                            "prefilter": reference.prefilter, "max_bounces": reference.max_bounces},
              "presets": rows}
    (args.out / "bench.json").write_text(json.dumps(report, indent=1))
    print(f"frames and bench.json in {args.out}", file=sys.stderr)
    return 0


def _references(scenes, reference, args, space) -> list[np.ndarray]:
    """Reference frames, reused from ``--out`` when rendered before with the same rigs, renderer
    version and reference settings (the file name carries the render cache key)."""
    import cv2

    from isu_validate.render import open_renderer
    with open_renderer(reference, args.rig, log_dir=args.out / "logs", timeout_s=3600, device="cpu") as r:
        paths = [args.out / f"reference-{r.cache_key(space.canonical(s))[:16]}.png" for s in scenes]
        todo = [(s, p) for s, p in zip(scenes, paths) if not p.is_file()]
        if todo:
            print(f"rendering {len(todo)} reference frame(s) at {reference.samples} spp (slow, done once)...",
                  file=sys.stderr)
        for scene, path in todo:   # the worker starts only if something is missing
            t = time.perf_counter()
            r.render(scene, path)
            print(f"  {path.name}: {time.perf_counter() - t:.0f} s", file=sys.stderr)
    return [cv2.imread(str(p)) for p in paths], paths


def _bench_preset(preset, scenes, refs, args, space, people: bool = True) -> dict:
    import cv2
    import numpy as np
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    from isu_validate.render import open_renderer
    from isu_validate.render.presets import SSIM_FLOORS
    times, psnr, ssim = [], [], []
    parts = {"people_s": [], "update_s": [], "render_s": [], "write_s": [], "worker_cpu_s": [], "footprint_s": []}
    with open_renderer(preset, args.rig, log_dir=args.out / "logs", device=args.render_device) as r:
        r.show_people = people
        tag = "" if people else "-nopeople"
        r.render(scenes[0], args.out / f"{preset.name}{tag}-warmup.png")   # kernel load, first BVH: not timed
        for k in range(args.repeat):
            for i, (scene, ref) in enumerate(zip(scenes, refs or [None] * len(scenes))):
                out = args.out / f"{preset.name}{tag}-{i}.png"
                result = r.render(scene, out)
                times.append(result.timings["total_s"])
                for key in parts:
                    parts[key].append(result.timings.get(key, 0.0))
                if k == 0 and refs is not None:
                    img = cv2.imread(str(out))
                    if img.shape != ref.shape:
                        img = cv2.resize(img, (ref.shape[1], ref.shape[0]), interpolation=cv2.INTER_CUBIC)
                    psnr.append(peak_signal_noise_ratio(ref, img, data_range=255))
                    ssim.append(structural_similarity(ref, img, channel_axis=2, data_range=255))
        width, height, device = r.render_rig.width, r.render_rig.height, r.preset.device
    return {"preset": preset.name, "render_device": device, "resolution": f"{width}x{height}",
            "samples": preset.samples, "denoise": preset.denoise, "prefilter": preset.prefilter,
            "max_bounces": preset.max_bounces,
            "s_per_frame": {"median": statistics.median(times), "min": min(times), "max": max(times)},
            "median_parts_s": {k: statistics.median(v) for k, v in parts.items()},
            "psnr_db": float(np.mean(psnr)) if psnr else None, "ssim": float(np.mean(ssim)) if ssim else None,
            "ssim_per_scene": [round(float(v), 5) for v in ssim], "ssim_floor": SSIM_FLOORS.get(preset.name),
            "frames": len(times)}


class _SUTCheck:
    """Share of VQA answers a SUT gives on a preset's frames that equal its answers on the references."""

    def __init__(self, spec: str, space, scenes, ref_paths):
        from isu_validate.sut import build_request, open_sut
        self.sut, self.space, self.scenes, self.build = open_sut(spec, space=space), space, scenes, build_request
        self.ref = [self._answers(s, p) for s, p in zip(scenes, ref_paths)]

    def _answers(self, scene, image) -> dict:
        response = self.sut.query(self.build(self.space, scene, image, "vqa"))
        return response.answers or {} if not response.error else {}

    def unchanged(self, frames) -> float | None:
        same = total = 0
        for scene, frame, ref in zip(self.scenes, frames, self.ref):
            got = self._answers(scene, frame)
            for key, answer in ref.items():
                total += 1
                same += got.get(key) == answer
        return same / total if total else None


def _floor(row: dict) -> str:
    floor = row.get("ssim_floor")
    if floor is None or row.get("ssim") is None:
        return ""
    return f" (floor {floor})" if row["ssim"] >= floor else f" (BELOW the floor {floor})"


def _print_row(row: dict) -> None:
    s = row["s_per_frame"]
    print(f"{row['preset']:>9} {row['resolution']:>8} {row['samples']:>4} spp {row['render_device']:>5}  "
          f"s/frame median {s['median']:.2f} (min {s['min']:.2f}, max {s['max']:.2f})  "
          f"PSNR {row['psnr_db']:.1f} dB  SSIM {row['ssim']:.4f}{_floor(row)}  "
          + (f"SUT unchanged {row['sut_unchanged']:.1%}  " if row.get("sut_unchanged") is not None else "") +
          f"[update {row['median_parts_s']['update_s']:.3f} render {row['median_parts_s']['render_s']:.2f} "
          f"write {row['median_parts_s']['write_s']:.2f}; worker CPU {row['median_parts_s']['worker_cpu_s']:.2f} s; "
          f"footprints {1000 * row['median_parts_s']['footprint_s']:.0f} ms]",
          flush=True)
    bare = row.get("without_people")
    if bare:
        cost = s["median"] - bare["s_per_frame"]["median"]
        cpu = row["median_parts_s"]["worker_cpu_s"] - bare["median_parts_s"]["worker_cpu_s"]
        print(f"{'':>9} without people: s/frame median {bare['s_per_frame']['median']:.2f}; the people cost "
              f"{cost:+.2f} s/frame ({cpu:+.2f} worker CPU s; "
              f"posing on the host {row['median_parts_s']['people_s']:.3f} s)",
              flush=True)
