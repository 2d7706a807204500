"""Optimisation-based neural style transfer (Gatys, Ecker, Bethge 2016) on the Caffe VGG19.

Defaults suit a CPU: a small image, few L-BFGS iterations, starting from the content image
(which keeps the scene's structure from the first step and converges in far fewer steps).
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Callable, Mapping, Sequence, Union

import torch

from isu_validate.errors import InputError

from .colour import preserve_colour
from .losses import content_loss, style_loss, tv_loss
from .style_set import mean_grams
from .vgg import VGG19, preprocess

STYLE_LAYERS = ("relu1_1", "relu2_1", "relu3_1", "relu4_1", "relu5_1")
CONTENT_LAYERS = ("relu4_2",)
# one style image, a style set's images, or their mean Grams (layer -> (1, C, C))
Style = Union[torch.Tensor, Sequence[torch.Tensor], Mapping[str, torch.Tensor]]


@dataclass(frozen=True)
class GatysConfig:
    content_layers: tuple[str, ...] = CONTENT_LAYERS
    style_layers: tuple[str, ...] = STYLE_LAYERS
    content_weight: float = 1.0
    style_weight: float = 10.0     # content and style losses start on the same scale (grams / CHW)
    tv_weight: float = 0.0
    optimizer: str = "lbfgs"      # or "adam"
    steps: int = 40               # L-BFGS iterations or Adam steps
    lr: float = 0.02              # Adam only; pixels live in 0..1
    size: int = 192               # longer side of the optimised image
    style_size: int | None = None  # longer side of the style image (default: size)
    init: str = "content"         # or "noise"
    pooling: str = "avg"
    preserve_colour: bool = False
    seed: int = 0

    def check(self) -> None:
        if self.optimizer not in ("lbfgs", "adam"):
            raise InputError(f"optimizer must be lbfgs or adam, got {self.optimizer!r}")
        if self.init not in ("content", "noise"):
            raise InputError(f"init must be content or noise, got {self.init!r}")
        if self.steps < 1 or self.size < 16:
            raise InputError("steps must be >= 1 and size >= 16 pixels")
        if not self.content_layers or not self.style_layers:
            raise InputError("give at least one content layer and one style layer")


@dataclass
class GatysResult:
    image: torch.Tensor                       # (1, 3, H, W) in 0..1
    losses: list[float] = field(default_factory=list)  # total loss per evaluation
    seconds: float = 0.0
    config: dict = field(default_factory=dict)


class GatysObjective:
    """Loss of a candidate image against fixed content activations and style Gram matrices: of one
    style image, the mean Grams of several (see ``style_set``), or such Grams computed once already
    (a mapping layer -> Gram: a style set styling many images pays for its photos once)."""

    def __init__(self, vgg: VGG19, content: torch.Tensor, style: Style, cfg: GatysConfig):
        self.vgg, self.cfg = vgg, cfg
        self.layers = set(cfg.content_layers) | set(cfg.style_layers)
        with torch.no_grad():
            self.content_targets = vgg(preprocess(content), cfg.content_layers)
        self.style_grams = _style_grams(vgg, style, cfg.style_layers)

    def __call__(self, x: torch.Tensor) -> torch.Tensor:
        feats = self.vgg(preprocess(x), self.layers)
        loss = self.cfg.content_weight * content_loss(feats, self.content_targets, self.cfg.content_layers)
        loss = loss + self.cfg.style_weight * style_loss(feats, self.style_grams, self.cfg.style_layers)
        if self.cfg.tv_weight:
            loss = loss + self.cfg.tv_weight * tv_loss(x)
        return loss


def stylize_gatys(content: torch.Tensor, style: Style, cfg: GatysConfig = GatysConfig(),
                  vgg: VGG19 | None = None, progress: Callable[[int, float], None] | None = None) -> GatysResult:
    """Stylise ``content`` (1, 3, H, W in 0..1, already at the working size) with ``style`` (one image,
    a style set's images, or their mean Grams)."""
    cfg.check()
    vgg = vgg or VGG19(cfg.pooling)
    content = content.to(vgg.device)   # the optimisation runs where the VGG is (``vgg.to(device)``)
    start = time.perf_counter()
    objective = GatysObjective(vgg, content, style, cfg)
    x = _initial(content, cfg).requires_grad_(True)
    losses: list[float] = []

    def evaluate() -> torch.Tensor:
        with torch.no_grad():
            x.clamp_(0, 1)  # pixels stay displayable; L-BFGS tolerates this projection in practice
        if optimiser is not None:
            optimiser.zero_grad()
        loss = objective(x)
        loss.backward()
        losses.append(loss.item())
        if progress:
            progress(len(losses), losses[-1])
        return loss

    if cfg.optimizer == "lbfgs":
        # a strong-Wolfe line search: with a fixed step L-BFGS overshoots on this loss's scale
        # and the loss can rise; the search costs a few extra evaluations per iteration
        optimiser = torch.optim.LBFGS([x], lr=1.0, max_iter=cfg.steps, history_size=20,
                                      tolerance_grad=0.0, tolerance_change=0.0, line_search_fn="strong_wolfe")
        optimiser.step(evaluate)
    else:
        optimiser = torch.optim.Adam([x], lr=cfg.lr)
        for _ in range(cfg.steps):
            evaluate()
            optimiser.step()
    out = x.detach().clamp(0, 1)
    if cfg.preserve_colour:
        out = preserve_colour(out, content)
    return GatysResult(out, losses, time.perf_counter() - start, asdict(cfg))


def _style_grams(vgg: VGG19, style: Style, layers: Sequence[str]) -> dict[str, torch.Tensor]:
    if isinstance(style, Mapping):
        missing = sorted(set(layers) - set(style))
        if missing:
            raise InputError(f"the style Grams lack the layers {missing}; compute them for {list(layers)}")
        return {layer: style[layer] for layer in layers}
    return mean_grams(vgg, [style] if isinstance(style, torch.Tensor) else list(style), layers)


def _initial(content: torch.Tensor, cfg: GatysConfig) -> torch.Tensor:
    if cfg.init == "content":
        return content.clone()
    gen = torch.Generator().manual_seed(cfg.seed)   # the CPU's: the same start on every device
    return torch.rand(content.shape, generator=gen, dtype=content.dtype).to(content.device)

