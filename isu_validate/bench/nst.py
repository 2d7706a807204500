"""``isu-validate bench nst``: Gatys steps against loss, structure and time; fast-model throughput;
with ``--pairs-scale N``: ``stylize --pairs`` on N pairs, fast (the default) against Gatys.

Without images it uses a synthetic cabin-like render and a noisy, tinted "photo" of it, so
the numbers are reproducible anywhere; pass --content and --style for real ones, or --pairs DIR.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from isu_validate.devices import add_device_argument, resolve_torch_device
from isu_validate.errors import InputError


def register_bench(sub) -> None:
    p = sub.add_parser("nst", help="style transfer: Gatys steps against loss and time; fast-model throughput")
    p.add_argument("--content", type=Path, help="a render (default: synthetic)")
    p.add_argument("--style", type=Path, help="a real photo (default: synthetic)")
    p.add_argument("--size", type=int, default=128, help="Gatys working size, longer side (default 128)")
    p.add_argument("--steps", default="5,10,20,40", help="Gatys L-BFGS iterations to compare (default 5,10,20,40)")
    p.add_argument("--optimizer", choices=("lbfgs", "adam"), default="lbfgs")
    p.add_argument("--model", type=Path, help="a trained fast model (default: an untrained one; same speed)")
    p.add_argument("--frames", type=int, default=10, help="640x480 frames for the fast-model throughput")
    p.add_argument("--train-steps", type=int, default=0, help="also time this many fast-model training steps")
    p.add_argument("--gap", type=int, default=0,
                   help="also: N synthetic renders and N 'photos' of other scenes; train the fast model on the "
                        "renders (--train-steps, default 100) and report FID/KID sim-real against nst-real")
    p.add_argument("--style-weight", type=float, default=1.0, help="style weight for the --gap training (default 1)")
    p.add_argument("--pairs-scale", type=int, default=0, metavar="N",
                   help="instead: `stylize --pairs` on N pairs (the paper's study: 53) with the fast method, "
                        "Gatys on --gatys-images of them; time and quality of both")
    p.add_argument("--pairs", type=Path, help="with --pairs-scale: a pairs directory whose samples are repeated "
                                              "to N (default: synthetic 640x480 pairs)")
    p.add_argument("--gatys-images", type=int, default=3, help="with --pairs-scale: pairs Gatys styles (default 3; "
                                                               "its total for N is extrapolated)")
    p.add_argument("--threads", type=int, default=None)
    add_device_argument(p)
    p.set_defaults(func=run)


def synthetic_render(width: int = 640, height: int = 480, seed: int = 0):
    """A flat-shaded 'render' of a cabin: window, two seats, heads; the layout varies with the seed."""
    from PIL import Image, ImageDraw
    rng = np.random.default_rng(seed)
    img = Image.new("RGB", (width, height), tuple(int(v) for v in rng.integers(55, 90, 3)))
    draw = ImageDraw.Draw(img)
    draw.rectangle([0, 0, width, int(height * rng.uniform(0.25, 0.4))], fill=(150, 170, 190))
    for x0 in (width // 8, width // 2 + width // 16):
        x0 += int(rng.integers(-width // 20, width // 20))
        draw.rounded_rectangle([x0, height // 3, x0 + width // 3, height - 20], 30,
                               fill=tuple(int(v) for v in rng.integers(25, 70, 3)))
        if rng.random() < 0.7:  # an occupant
            draw.ellipse([x0 + width // 12, height // 5, x0 + width // 5, height // 5 + height // 6],
                         fill=tuple(int(v) for v in rng.integers(140, 220, 3)))
    return img


def camera_look(img, seed: int = 0):
    """What a real cabin camera adds: optical blur, a colour cast, lifted blacks, sensor noise."""
    from PIL import Image, ImageFilter
    rng = np.random.default_rng(seed)
    photo = np.asarray(img.filter(ImageFilter.GaussianBlur(2)), np.float32) * np.array([1.05, 0.95, 0.8]) + 15
    photo += rng.normal(0, 10, photo.shape)
    return Image.fromarray(np.clip(photo, 0, 255).astype(np.uint8))


def synthetic_pair(width: int = 640, height: int = 480, seed: int = 0):
    render = synthetic_render(width, height, seed)
    return render, camera_look(render, seed)


def _images(args, folder: Path) -> tuple[Path, Path]:
    if args.content and args.style:
        return args.content, args.style
    render, photo = synthetic_pair()
    render.save(folder / "render.png")
    photo.save(folder / "photo.png")
    return folder / "render.png", folder / "photo.png"


def gatys_table(content_path: Path, style_path: Path, size: int, steps: list[int], optimizer: str,
                device: str = "cpu") -> None:
    import torch  # imported here: registering the bench must not load torch
    from style_transfer.gatys import GatysConfig, stylize_gatys
    from style_transfer.imageio import load_image
    from style_transfer.preservation import luminance, ssim_luma
    from style_transfer.vgg import VGG19
    vgg = VGG19("avg").to(device)
    content, style = load_image(content_path, size), load_image(style_path, size)
    luma_in = luminance(content[0].permute(1, 2, 0).numpy().astype(np.float64))
    print(f"Gatys ({optimizer}), {tuple(content.shape[-2:])} pixels, {torch.get_num_threads()} torch threads")
    print(f"{'steps':>6} {'evals':>6} {'loss/loss0':>11} {'SSIM-luma':>10} {'seconds':>8}")
    for n in steps:
        r = stylize_gatys(content, style, GatysConfig(steps=n, size=size, optimizer=optimizer), vgg)
        ssim = ssim_luma(luma_in, luminance(r.image[0].permute(1, 2, 0).cpu().numpy().astype(np.float64)))
        print(f"{n:>6} {len(r.losses):>6} {r.losses[-1] / r.losses[0]:>11.4f} {ssim:>10.3f} {r.seconds:>8.1f}")


def fast_table(model: Path | None, frames: int, folder: Path, device: str = "cpu") -> None:
    import torch  # imported here: registering the bench must not load torch
    from style_transfer.fast import load_model, stylize_fast
    from style_transfer.fast_net import FastStyleNet
    from style_transfer.imageio import load_image, save_image
    net = (load_model(model)[0] if model else FastStyleNet().eval()).to(device)
    render, _ = synthetic_pair()
    render.save(folder / "frame.png")
    x = load_image(folder / "frame.png")
    stylize_fast(net, x)  # warm-up

    def rate(work) -> tuple[float, float]:
        """Median and best of 3 rounds: a shared machine's other jobs only ever slow a round down."""
        rates = []
        for _ in range(3):
            start = time.perf_counter()
            for i in range(frames):
                work(i)
            rates.append(frames / (time.perf_counter() - start))
        return float(np.median(rates)), max(rates)
    net_only = rate(lambda i: stylize_fast(net, x, i))
    files = rate(lambda i: save_image(stylize_fast(net, load_image(folder / "frame.png"), i), folder / f"out{i}.png"))
    print(f"\nfast model {net.cfg}, 640x480, {torch.get_num_threads()} torch threads (median / best of 3 rounds)")
    print(f"   network only: {net_only[0]:.1f} / {net_only[1]:.1f} images/s; "
          f"file to file (PNG read + net + PNG write): {files[0]:.1f} / {files[1]:.1f} images/s")


def train_table(content: Path, style: Path, steps: int, folder: Path, device: str = "cpu") -> None:
    from style_transfer.fast import FastTrainConfig, train_fast
    report = train_fast(style, [content], folder / "m.pt", FastTrainConfig(steps=steps), resume=False, device=device)
    print(f"\nfast-model training: {steps} steps (batch 2, crop 128) in {report.seconds:.1f} s "
          f"({report.seconds / steps:.2f} s/step); loss {report.losses[0]:.4g} -> {report.losses[-1]:.4g}")


def gap_table(n: int, train_steps: int, folder: Path, style_weight: float = 1.0) -> None:
    """Does style transfer narrow the sim-to-real gap? Renders and photos show different scenes,
    as in a real study; one photo is the style. Small images keep it to minutes on a CPU."""
    from isu_validate.realism import FeatureExtractor, MetricSettings, compare_features
    from style_transfer.fast import FastTrainConfig, load_model, stylize_fast, train_fast
    from style_transfer.imageio import load_image, save_image
    sets = {name: folder / name for name in ("sim", "real", "nst")}
    for d in sets.values():
        d.mkdir()
    for i in range(n):
        synthetic_render(320, 240, seed=1000 + i).save(sets["sim"] / f"{i:03d}.png")
        camera_look(synthetic_render(320, 240, seed=2000 + i), seed=i).save(sets["real"] / f"{i:03d}.png")
    renders = sorted(sets["sim"].glob("*.png"))
    start = time.perf_counter()
    cfg = FastTrainConfig(steps=train_steps, style_weight=style_weight)
    train_fast(sets["real"] / "000.png", renders, folder / "gap.pt", cfg, resume=False)
    trained = time.perf_counter() - start
    net, _ = load_model(folder / "gap.pt")
    for path in renders:
        save_image(stylize_fast(net, load_image(path)), sets["nst"] / path.name)
    ex = FeatureExtractor(batch_size=8)
    feats = {k: ex.features(sorted(d.glob("*.png"))) for k, d in sets.items()}
    metric = MetricSettings(bootstrap=100, kid_subsets=100, seed=0)
    print(f"\nsim-to-real gap, {n} renders vs {n} photos of other scenes, 320x240; fast model trained "
          f"{train_steps} steps (style weight {style_weight}) in {trained:.0f} s")
    for a, b in (("sim", "real"), ("nst", "real"), ("sim", "nst")):
        r = compare_features(feats[a], feats[b], metric)
        print(f"   {a}-{b}: FID {r.fid:8.2f} [{r.fid_ci[0]:.2f}, {r.fid_ci[1]:.2f}]   "
              f"KID {r.kid_mean:.4f} +- {r.kid_std:.4f} (subset {r.settings['kid_subset_size']})")


def run(args) -> int:
    import torch  # imported here: registering the bench must not load torch
    if args.threads:
        torch.set_num_threads(args.threads)
    if args.pairs_scale:
        return pairs_table(args.pairs_scale, args.pairs, args.gatys_images, args.threads or torch.get_num_threads(),
                           args.device)
    device = resolve_torch_device(args.device)
    print(f"bench nst on {device.describe()}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        content, style = _images(args, folder)
        gatys_table(content, style, args.size, [int(s) for s in args.steps.split(",") if s.strip()], args.optimizer,
                    device.name)
        if args.frames:
            fast_table(args.model, args.frames, folder, device.name)
        if args.train_steps:
            train_table(content, style, args.train_steps, folder, device.name)
        if args.gap:
            gap_table(args.gap, args.train_steps or 100, folder, args.style_weight)
    return 0


# ---- --pairs-scale N: the paper's study size through the real `stylize --pairs` path

def scaled_pairs(n: int, source: Path | None, folder: Path) -> Path:
    """N pairs in ``folder``: ``source``'s samples repeated (sim.png and real frames), or synthetic ones
    (a 640x480 cabin render and its 'photo': the same scene through ``camera_look``)."""
    import shutil

    from isu_validate.pairs import PairsDir
    root = folder / "pairs"
    originals = [s for s in PairsDir(source).samples() if s.sim.is_file()] if source else []
    if source and not originals:
        raise InputError(f"pairs directory {source} has no <sample>/sim.png to repeat")
    for i in range(n):
        sample = root / f"S{i + 1:02d}"
        (sample / "real").mkdir(parents=True)
        if originals:
            orig = originals[i % len(originals)]
            shutil.copyfile(orig.sim, sample / "sim.png")
            for frame in orig.real_frames():
                shutil.copyfile(frame, sample / "real" / frame.name)
        else:
            render = synthetic_render(640, 480, seed=i)
            render.save(sample / "sim.png")
            camera_look(synthetic_render(640, 480, seed=i), seed=i).save(sample / "real" / "frame_0000.png")
    return root


def _stylize(argv: list[str], report: Path) -> tuple[dict, float, float]:
    """Run `isu-validate stylize` as a user does (its own process, imports included); its report, wall and
    CPU seconds."""
    import json
    import resource
    import subprocess
    import sys

    def children_cpu() -> float:
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime
    wall, cpu = time.perf_counter(), children_cpu()
    done = subprocess.run([sys.executable, "-m", "isu_validate.cli", "stylize", *argv], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"stylize {' '.join(argv)} failed ({done.returncode}): {done.stderr[-800:]}")
    return json.loads(report.read_text()), time.perf_counter() - wall, children_cpu() - cpu


def _quality(distance, records: list[dict]) -> dict:
    """Style distance (all images, same measure) and preservation means of a run's records."""
    from style_transfer.distance import gap_closed
    d = [distance(Path(r["output"])) for r in records]
    d0 = [distance(Path(r["source"])) for r in records]
    return {"distance": float(np.mean(d)), "closed": float(np.mean([gap_closed(a, b) for a, b in zip(d, d0)])),
            "ssim": float(np.mean([r["ssim_luma"] for r in records])),
            "edge": float(np.mean([r["edge_agreement"] for r in records]))}


def pairs_table(n: int, source: Path | None, gatys_images: int, threads: int, device: str = "auto") -> int:
    """The fast default on N pairs, end to end, against Gatys on the first few of them."""
    import os
    import shutil

    from style_transfer.distance import StyleDistance
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        pairs = scaled_pairs(n, source, folder)
        common = ["--threads", str(threads), "--device", device]
        fast_run = ["--pairs", str(pairs), "--model-cache", str(folder / "cache"), *common]
        fast, fast_wall, fast_cpu = _stylize(fast_run, pairs / "nst.json")
        _, rerun_wall, _ = _stylize(fast_run, pairs / "nst.json")
        few = folder / "few"
        for sample in sorted(pairs.iterdir())[:gatys_images]:
            if sample.is_dir():
                shutil.copytree(sample, few / sample.name, ignore=shutil.ignore_patterns("nst.png"))
        styles = [a for p in fast["settings"]["styles"] for a in ("--style", p)]  # the same style set
        gatys, gatys_wall, gatys_cpu = _stylize(["--pairs", str(few), "--method", "gatys", "--style-distance", "0",
                                                 *styles, *common], few / "nst.json")
        distance = StyleDistance([Path(p) for p in fast["settings"]["styles"]])
        fast_few = [r for r in fast["images"] if Path(r["source"]).parent.name in {p.name for p in few.iterdir()}]
        q_fast, q_gatys = _quality(distance, fast_few), _quality(distance, gatys["images"])
        q_fast_all = _quality(distance, fast["images"])
    _print_pairs(n, source, threads, load, fast, fast_wall, fast_cpu, rerun_wall, gatys, gatys_wall, gatys_cpu,
                 q_fast, q_gatys, q_fast_all)
    return 0


def _print_pairs(n, source, threads, load, fast, fast_wall, fast_cpu, rerun_wall, gatys, gatys_wall, gatys_cpu,
                 q_fast, q_gatys, q_fast_all) -> None:
    import os
    k, settings = gatys["count"], fast["settings"]
    print(f"stylize --pairs on {n} pairs ({'repeated from ' + str(source) if source else 'synthetic 640x480'}), "
          f"{threads} torch threads; style set: {len(settings['styles'])} real frame(s); "
          f"load average {load:.1f} before, {os.getloadavg()[0]:.1f} after (a busy machine slows every figure)")
    print(f"fast: {settings['train']['steps']} training steps, net at {settings['fast_size'] or 'full'} px; "
          f"gatys: {k} pair(s) styled, its total for {n} extrapolated; quality on those {k} image(s); "
          "style distance at 256 px, relu1_1..relu5_1")
    print(f"{'method':<7} {'train s':>8} {'s/image':>8} {f'total s ({n})':>14} {'CPU s':>7} "
          f"{'gap closed':>11} {'style dist':>11} {'SSIM-luma':>10} {'edges':>6}")
    rows = {"fast": (f"{settings['train_seconds']:.1f}", fast["images"], f"{fast_wall:.0f}", fast_cpu, q_fast),
            "gatys": ("-", gatys["images"], f"~{gatys_wall / k * n:.0f}", gatys_cpu / k * n, q_gatys)}
    for name, (train, images, total, cpu, q) in rows.items():
        per_image = np.mean([r["seconds"] for r in images])
        print(f"{name:<7} {train:>8} {per_image:>8.2f} {total:>14} {cpu:>7.0f} {q['closed']:>11.3f} "
              f"{q['distance']:>11.1f} {q['ssim']:>10.3f} {q['edge']:>6.3f}")
    ratio = q_fast["distance"] / q_gatys["distance"]
    print(f"fast against gatys: {gatys_wall / k * n / fast_wall:.0f}x faster for {n} pairs; style distance "
          f"{ratio:.2f}x Gatys's; SSIM-luma {q_fast['ssim'] - q_gatys['ssim']:+.3f}; "
          f"edges {q_fast['edge'] - q_gatys['edge']:+.3f}")
    print(f"fast on all {n}: gap closed {q_fast_all['closed']:.3f}, SSIM-luma {q_fast_all['ssim']:.3f}; "
          f"the same command again (cached net, every pair kept): {rerun_wall:.1f} s")
