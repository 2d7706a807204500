"""``isu-validate dataset``: render a training dataset (images, metadata.jsonl, COCO masks, VQA chats),
uniformly over the space or focused where earlier runs failed; ``--resume`` continues one."""
from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from ..dataset.settings import DatasetSettings
from ..devices import add_device_argument, add_render_device_argument
from . import add_variety_arguments

_DEFAULTS = DatasetSettings()
# options that decide the images: left out on --resume, they take the stored value
_IDENTITY = ("n", "seed", "space", "preset", "camera", "extrinsics_from", "cabin", "prompt_style", "from_runs", "focus",
             "styles", "style_models", "style_size", "style_steps", "camera_jitter", "sensor_effects",
             "camera_mix", "renderer_factory")


def register(sub) -> None:
    p = sub.add_parser("dataset", help="render a training dataset: images, truth, COCO masks, VQA chats",
                       description="Render N scenes into a dataset folder: images/, metadata.jsonl (scene, truth, "
                                   "occluded per image; Hugging Face image-folder layout), annotations.json (COCO "
                                   "instance masks), vqa.jsonl (prompt and expected answer as chat messages), "
                                   "dataset.json and DATASET_CARD.md. With --from-run the scenes are drawn near the "
                                   "runs' failing tests (never one of their scenes). Progress and an ETA go to "
                                   "stderr; every image is committed as it is made, so --resume after a kill "
                                   "continues with none twice and none lost.")
    p.add_argument("--out", type=Path, required=True, help="the dataset folder (new, or one to --resume)")
    p.add_argument("--n", type=int, help=f"renders in the dataset (default {_DEFAULTS.n})")
    p.add_argument("--seed", type=int, help=f"seed of the scenes (default {_DEFAULTS.seed})")
    p.add_argument("--space", help=f"scene space name or .toml path (default {_DEFAULTS.space})")
    p.add_argument("--preset", help=f"render preset: draft | standard | final (default {_DEFAULTS.preset})")
    p.add_argument("--camera", help="camera rig name or .toml path; a rig with an imaging model develops the renders "
                                    f"as that camera would, as `run --camera` does (default {_DEFAULTS.camera})")
    p.add_argument("--extrinsics-from", metavar="RIG",
                   help="take the camera's pose in the cabin from this registered rig")
    p.add_argument("--cabin", help=f"cabin rig name or .toml path (default {_DEFAULTS.cabin})")
    p.add_argument("--prompt-style", choices=("paper", "compact"),
                   help=f"wording of the VQA prompt in vqa.jsonl, as `run --prompt-style` (default "
                        f"{_DEFAULTS.prompt_style})")
    p.add_argument("--from-run", dest="from_runs", nargs="+", metavar="RUN",
                   help="runs (or folders of runs) to focus on; their scenes never enter the dataset")
    p.add_argument("--focus", help="with --from-run: failing (default; the failure regions `report` prints and the "
                                   "failing tests), passing, or rule:\"FEATURE = VALUE and ...\" (one region by hand)")
    p.add_argument("--style", dest="styles", nargs="+", metavar="IMG",
                   help="style images: each adds a style-transferred copy of every render (labels and masks shared)")
    p.add_argument("--style-model", dest="style_models", nargs="+", metavar="MODEL",
                   help="fast nets of `stylize train`: a style image with its net is transferred in one forward "
                        "pass; the others by Gatys' optimisation (seconds per image)")
    p.add_argument("--style-size", type=int, help=f"Gatys: longer side optimised, px (default {_DEFAULTS.style_size})")
    p.add_argument("--style-steps", type=int,
                   help=f"Gatys: L-BFGS iterations per image (default {_DEFAULTS.style_steps})")
    add_variety_arguments(p)
    p.add_argument("--resume", action="store_true",
                   help="continue the dataset in --out; options left out keep their stored values, others must match")
    p.add_argument("--workers", type=int, default=1, help="local render processes (default 1)")
    p.add_argument("--cluster", metavar="ADDRESS", help="a Dask scheduler to render on, as `run --cluster`")
    add_render_device_argument(p)
    add_device_argument(p)
    # module:function(space) -> renderer: the tests make datasets without Blender
    p.add_argument("--renderer-factory", help=argparse.SUPPRESS)
    p.set_defaults(func=run, interrupted="interrupted; every finished image is kept (continue with --resume)")


def run(args) -> int:
    from ..dataset import DatasetDir, build_dataset

    given = {name: _value(getattr(args, name)) for name in _IDENTITY if getattr(args, name) is not None}
    folder = DatasetDir(args.out)
    base = DatasetSettings.from_dict(folder.info()["settings"]) if args.resume and folder.is_dataset() else _DEFAULTS
    settings = replace(base, **given, workers=args.workers, cluster=args.cluster, render_device=args.render_device,
                       device=args.device)
    summary = build_dataset(settings, args.out, resume=args.resume)
    copies = summary.images - summary.renders
    print(f"dataset {summary.out}: {summary.renders} renders" + (f" + {copies} style copies" if copies else "")
          + f" ({summary.images} images; {summary.skipped} unusable frames replaced)")
    if summary.made_now:
        print(f"{summary.made_now} rendered now in {summary.seconds:.1f} s: {summary.renders_per_s:.2f} renders/s")
    print("files: images/, metadata.jsonl, annotations.json, vqa.jsonl, dataset.json, DATASET_CARD.md")
    return 0


def _value(value):
    return tuple(value) if isinstance(value, list) else value
