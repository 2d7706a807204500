"""Training and applying the feed-forward style network for one real style image or a style set.

Training (Johnson et al. 2016) minimises the Gatys content and style losses of the network's
output over crops of many renders, so afterwards one forward pass stylises a frame.
Training checkpoints every few steps and resumes from the checkpoint when interrupted.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import torch
import torch.nn.functional as F

from isu_validate.atomic import atomic_path
from isu_validate.errors import InputError, InputNotFound

from .fast_net import FastNetConfig, FastStyleNet
from .imageio import load_image
from .losses import content_loss, style_loss, tv_loss
from .style_set import file_sha256, fingerprint, load_style_grams
from .vgg import VGG19, preprocess

FORMAT = "isu-validate-fast-style/1"


@dataclass(frozen=True)
class FastTrainConfig:
    net: FastNetConfig = field(default_factory=FastNetConfig)
    steps: int = 300
    batch_size: int = 2
    crop: int = 128               # training crop side; the net is fully convolutional
    style_size: int = 256         # longer side of the style image when taking its Gram matrices
    content_layers: tuple[str, ...] = ("relu2_2",)   # Johnson's choice: keeps edges, frees colour
    style_layers: tuple[str, ...] = ("relu1_1", "relu2_1", "relu3_1", "relu4_1")
    content_weight: float = 1.0
    style_weight: float = 1.0     # bench nst --gap: 1 narrowed KID by 8.5%, 10 widened the gap (over-recolours)
    tv_weight: float = 0.0
    lr: float = 1e-3
    pooling: str = "avg"
    seed: int = 0
    checkpoint_every: int = 25


@dataclass
class TrainReport:
    steps_done: int
    final_loss: float
    seconds: float
    losses: list[float]


class CropSampler:
    """Seeded random crops from renders held in memory at a small size."""

    def __init__(self, paths: Sequence[Path], crop: int, seed: int):
        if not paths:
            raise InputError("training needs at least one content image (a folder of renders)")
        self.crop = crop
        # keep a margin above the crop so crops vary in position
        self.images = [self._fit_short_side(load_image(p), round(crop * 1.25)) for p in paths]
        self.gen = torch.Generator().manual_seed(seed)

    @staticmethod
    def _fit_short_side(x: torch.Tensor, side: int) -> torch.Tensor:
        h, w = x.shape[-2:]
        scale = side / min(h, w)
        size = (max(side, round(h * scale)), max(side, round(w * scale)))
        return torch.nn.functional.interpolate(x, size=size, mode="bilinear", antialias=True, align_corners=False)

    def batch(self, n: int) -> torch.Tensor:
        picks = torch.randint(len(self.images), (n,), generator=self.gen).tolist()
        crops = []
        for i in picks:
            img = self.images[i]
            top = int(torch.randint(img.shape[-2] - self.crop + 1, (1,), generator=self.gen))
            left = int(torch.randint(img.shape[-1] - self.crop + 1, (1,), generator=self.gen))
            crops.append(img[..., top:top + self.crop, left:left + self.crop])
        return torch.cat(crops).clamp(0, 1)


def train_fast(style_path: Path | Sequence[Path], content_paths: Sequence[Path], out: Path,
               cfg: FastTrainConfig = FastTrainConfig(), resume: bool = True,
               progress: Callable[[int, int, float], None] | None = None, device: str = "cpu") -> TrainReport:
    """Train a network for ``style_path`` (one photo, or a style set: their mean Grams) on crops of
    ``content_paths`` on ``device`` (a torch device name); write it to ``out``. The net starts from the
    same seeded weights and sees the same crops on every device; the crops are drawn on the CPU."""
    styles = [Path(style_path)] if isinstance(style_path, (str, Path)) else [Path(p) for p in style_path]
    torch.manual_seed(cfg.seed)
    vgg = VGG19(cfg.pooling).to(device)
    net = FastStyleNet(cfg.net).to(device)
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    sampler = CropSampler(content_paths, cfg.crop, cfg.seed)
    style_grams = load_style_grams(vgg, styles, cfg.style_size, cfg.style_layers)
    ckpt = Path(str(out) + ".ckpt")
    step, losses = _resume(ckpt, net, opt, sampler) if resume and ckpt.exists() else (0, [])
    start = time.perf_counter()
    layers = set(cfg.content_layers) | set(cfg.style_layers)
    while step < cfg.steps:
        batch = sampler.batch(cfg.batch_size).to(device)
        with torch.no_grad():
            targets = vgg(preprocess(batch), cfg.content_layers)
        styled = net(batch, seed=cfg.seed + step)  # fresh noise each step: the net learns its statistics
        feats = vgg(preprocess(styled), layers)
        loss = cfg.content_weight * content_loss(feats, targets, cfg.content_layers) \
            + cfg.style_weight * style_loss(feats, style_grams, cfg.style_layers)
        if cfg.tv_weight:
            loss = loss + cfg.tv_weight * tv_loss(styled)
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        losses.append(loss.item())
        if progress:
            progress(step, cfg.steps, losses[-1])
        if step % cfg.checkpoint_every == 0 and step < cfg.steps:
            _atomic_save({"step": step, "losses": losses, "net": net.state_dict(), "opt": opt.state_dict(),
                          "rng": sampler.gen.get_state()}, ckpt)
    net.eval()
    meta = {**_style_meta(styles), "content_images": len(content_paths), "trained_on": str(device),
            "steps_done": step, "final_loss": losses[-1] if losses else None, "train": _plain(asdict(cfg))}
    save_model(net, out, meta)
    ckpt.unlink(missing_ok=True)
    return TrainReport(step, losses[-1] if losses else float("nan"), time.perf_counter() - start, losses)


def _style_meta(styles: list[Path]) -> dict:
    # "style"/"style_sha256" name the one photo (what `stylize --model --style` checks); a set has several
    meta = {"styles": [str(p) for p in styles], "style_sha256s": [file_sha256(p) for p in styles],
            "style_set_sha256": fingerprint(styles)}
    if len(styles) == 1:
        meta |= {"style": str(styles[0]), "style_sha256": meta["style_sha256s"][0]}
    return meta


def _resume(ckpt: Path, net, opt, sampler) -> tuple[int, list[float]]:
    state = torch.load(ckpt, map_location="cpu", weights_only=True)   # loading copies onto the net's device
    net.load_state_dict(state["net"])
    opt.load_state_dict(state["opt"])
    sampler.gen.set_state(state["rng"])
    return int(state["step"]), list(state["losses"])


def _plain(d: dict) -> dict:
    return {k: (list(v) if isinstance(v, tuple) else _plain(v) if isinstance(v, dict) else v) for k, v in d.items()}


def _atomic_save(obj, path: Path) -> None:
    with atomic_path(path) as tmp:
        torch.save(obj, tmp)


def save_model(net: FastStyleNet, path: Path, meta: dict) -> Path:
    _atomic_save({"format": FORMAT, "net": net.cfg.to_dict(), "state_dict": net.state_dict(), "meta": meta}, Path(path))
    return Path(path)


def load_model(path: Path) -> tuple[FastStyleNet, dict]:
    path = Path(path)
    if not path.is_file():
        raise InputNotFound(f"fast style model {path} does not exist; train one with "
                                "`isu-validate stylize train --style REAL.png --content RENDERS/ --out MODEL`")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises several types for damaged files
        raise InputError(f"cannot read fast style model {path}: {exc}; retrain it") from exc
    if not isinstance(state, dict) or state.get("format") != FORMAT:
        raise InputError(f"{path} is not an isu-validate fast style model (format {FORMAT})")
    net = FastStyleNet(FastNetConfig(**state["net"]))
    net.load_state_dict(state["state_dict"])
    return net.eval(), state["meta"]


def stylize_fast(net: FastStyleNet, image: torch.Tensor, seed: int = 0, size: int | None = None) -> torch.Tensor:
    """One forward pass: (1, 3, H, W) 0..1 in and out; ``seed`` fixes the noise. With ``size`` the net runs
    at that longer side (the scale it was trained at) and its change, upsampled, is added to the image:
    the look changes as trained while the scene's fine detail passes through untouched."""
    image = image.to(next(net.parameters()).device)   # where the net is (``net.to(device)``)
    with torch.inference_mode():
        if not size or max(image.shape[-2:]) <= size:
            return net(image, seed)
        scale = size / max(image.shape[-2:])
        small = F.interpolate(image, scale_factor=scale, mode="bilinear", antialias=True, align_corners=False)
        change = net(small, seed) - small
        return (image + F.interpolate(change, size=image.shape[-2:], mode="bilinear", align_corners=False)).clamp(0, 1)
