"""Fine-tuning the reference ISU's backbone on its own training renders (``reference train --fine-tune``).

The frozen ImageNet backbone's pooled features find a rendered phone in the hand poorly: a linear head on them
reads it at 0.62-0.83 on its own held-out side-camera renders (README, "Sim-to-real transfer"). Training the
backbone's last blocks on the renders, every predicted feature at once, with photometric and framing noise so that
no one rendered colour or crop carries an answer, reads it at 0.76-0.88 on the same renders. The heads are then
fitted as always on the tuned backbone's features (``heads.py``), so everything downstream reads a tuned model as it
reads a frozen one. On real photos it is no transfer gain (README): an option, off by default.

Only rendered images are ever trained on here. A fine-tune commits a checkpoint after every epoch and resumes from
it; each epoch's randomness is seeded from (seed, epoch), so a resumed fine-tune ends with the weights an
uninterrupted one would have (to the BLAS kernels' last digits).
"""
from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

from ..atomic import atomic_path
from ..errors import InputError
from .backbone import Backbone, read_rgb

WEIGHTS_FILE = "backbone.pt"   # a tuned model's backbone, beside its heads
BLOCKS = 16                    # EfficientNet-Lite0's mobile blocks


@dataclass(frozen=True)
class FineTune:
    """What a fine-tune trains and how (the model card records it). Chosen on the side recipe's renders alone
    (README; scratch runs with two temporary heads): the last 6 of the 16 blocks at lr 3e-4 for 12 epochs read the
    phone better on held-out renders than the last 3 (0.90 against 0.78), and with the colour, blur and noise
    augmentation better than with crops alone (0.90, 0.81)."""
    blocks: int = 6            # the backbone's last N mobile blocks are trained (and its last convolution)
    epochs: int = 12
    learning_rate: float = 3e-4   # the blocks'; the temporary heads learn 10x faster
    batch: int = 16
    weight_decay: float = 1e-2
    seed: int = 0

    def __post_init__(self):
        if not 1 <= self.blocks <= BLOCKS:
            raise InputError(f"--fine-tune {self.blocks}: EfficientNet-Lite0 has 16 blocks; train 1 to 16 of them")
        if self.epochs < 1 or self.batch < 1 or self.learning_rate <= 0:
            raise InputError("a fine-tune needs at least one epoch, a batch of at least 1 and a positive learning rate")

    @classmethod
    def optional(cls, blocks: int | None, seed: int) -> "FineTune | None":
        """The settings a command's or recipe's BLOCKS asks for (None: no fine-tune; 0 is refused, not ignored)."""
        return None if blocks is None else cls(blocks=blocks, seed=seed)

    @property
    def key(self) -> str:
        return hashlib.sha256(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:12]


def fine_tune_backbone(backbone: Backbone, images: list[Path], scenes: list[dict], space, settings: FineTune,
                       checkpoint: Path | None = None, stream=None) -> dict:
    """Train ``backbone``'s last ``settings.blocks`` blocks on the images, one temporary linear head per predicted
    feature (the answers a scene's label has; a feature the frame hides is not learnt from). Leaves the tuned
    weights in ``backbone`` (``Backbone.tune``) and returns what the card records."""
    stream = stream or sys.stderr
    pixels = backbone.pixels([read_rgb(path) for path in images])
    targets, classes = _targets(space, scenes)
    trainer = _Trainer(backbone, classes, settings)
    first = trainer.resume(checkpoint) if checkpoint else 0
    losses = []
    for epoch in range(first, settings.epochs):
        losses.append(trainer.epoch(pixels, targets, epoch))
        if checkpoint:
            trainer.commit(checkpoint, epoch + 1)
        print(f"fine-tune: epoch {epoch + 1}/{settings.epochs}, loss {losses[-1]:.3f}", file=stream, flush=True)
    backbone.tune(trainer.tuned_state(), settings.blocks)
    return {**asdict(settings), "images": len(images), "features": list(classes),
            "last_epoch_loss": round(losses[-1], 4) if losses else None}


def _targets(space, scenes: list[dict]):
    """(n, features) class indices, -1 where a scene lacks the feature; the classes each index names."""
    import torch

    classes = {f.name: sorted({f.truth(v) for v in f.values}) for f in space.predicted}
    classes = {name: answers for name, answers in classes.items() if len(answers) > 1}
    target = torch.full((len(scenes), len(classes)), -1, dtype=torch.long)
    for i, scene in enumerate(scenes):
        for j, (name, answers) in enumerate(classes.items()):
            if name in scene:
                target[i, j] = answers.index(space.features[name].truth(scene[name]))
    if not (target >= 0).any():
        raise InputError("no training scene has a predicted feature to fine-tune on")
    return target, classes


class _Trainer:
    """The backbone's tuned part, the temporary heads, the optimiser and the augmentation."""

    def __init__(self, backbone: Backbone, classes: dict[str, list[str]], settings: FineTune):
        import torch

        self.torch, self.settings, self.backbone = torch, settings, backbone
        model = backbone.model
        first_tuned = BLOCKS - settings.blocks
        self.frozen_blocks, self.tuned_blocks = model._blocks[:first_tuned], model._blocks[first_tuned:]
        self.frozen = [model._conv_stem, model._bn0, *self.frozen_blocks]
        self.tuned = [*self.tuned_blocks, model._conv_head, model._bn1]
        torch.manual_seed(settings.seed)
        self.where = backbone.device.name   # the tuned part and the heads train where the backbone runs
        self.heads = torch.nn.ModuleList(torch.nn.Linear(1280, len(answers)) for answers in classes.values())
        self.heads.to(self.where)
        self.dropout = torch.nn.Dropout(0.3)
        for module in self.frozen:
            module.requires_grad_(False)
        for module in self.tuned:
            module.requires_grad_(True)
        self.optimiser = torch.optim.AdamW(
            [{"params": [p for m in self.tuned for p in m.parameters()], "lr": settings.learning_rate},
             {"params": self.heads.parameters(), "lr": settings.learning_rate * 10}],
            weight_decay=settings.weight_decay)
        self.augment = _augmentation(backbone.size)

    def epoch(self, pixels, targets, epoch: int) -> float:
        torch, s = self.torch, self.settings
        torch.manual_seed(s.seed * 1000 + epoch)   # an epoch's crops, colours and order: the same after a resume
        self._lr(epoch)
        self._mode(train=True)
        order, total = torch.randperm(len(pixels)), 0.0
        for start in range(0, len(pixels), s.batch):
            index = order[start:start + s.batch]
            x = self.backbone.normalise(self._noisy(torch.stack([self.augment(image) for image in pixels[index]])))
            loss = self._loss(self._pooled(x.to(self.where)), targets[index].to(self.where))
            self.optimiser.zero_grad()
            loss.backward()
            self.optimiser.step()
            total += float(loss.detach()) * len(index)
        self._mode(train=False)
        return total / len(pixels)

    def _lr(self, epoch: int) -> None:
        """A cosine decay after one warm-up epoch: a closed form of the epoch, so that a resume needs no
        scheduler state."""
        import math

        s = self.settings
        factor = 0.5 if epoch == 0 else 0.5 * (1 + math.cos(math.pi * epoch / s.epochs))
        for group, base in zip(self.optimiser.param_groups, (s.learning_rate, s.learning_rate * 10)):
            group["lr"] = base * factor

    def _noisy(self, x):
        torch = self.torch
        noise = torch.randn(x.shape) * torch.rand(len(x), 1, 1, 1) * 8.0   # sensor noise up to 8 grey levels
        return (x.float() + noise).clamp(0, 255)

    def _pooled(self, x):
        model, torch = self.backbone.model, self.torch
        with torch.no_grad():
            x = model._swish(model._bn0(model._conv_stem(x)))
            for block in self.frozen_blocks:
                x = block(x)
        for block in self.tuned_blocks:
            x = block(x)
        x = model._swish(model._bn1(model._conv_head(x)))
        return self.dropout(x.mean((2, 3)))

    def _loss(self, pooled, target):
        torch = self.torch
        losses = []
        for j, head in enumerate(self.heads):
            known = target[:, j] >= 0
            if known.any():
                losses.append(torch.nn.functional.cross_entropy(head(pooled[known]), target[known, j]))
        return torch.stack(losses).mean()

    def _mode(self, train: bool) -> None:
        """Only the tuned blocks learn (and their batch norms track the renders); the frozen ones stay as
        ImageNet left them."""
        self.backbone.model.train(False)
        self.dropout.train(train)
        for module in self.tuned:
            module.train(train)

    def tuned_state(self) -> dict:
        return {name: tensor.detach().cpu().clone() for name, tensor in self.backbone.model.state_dict().items()
                if _is_tuned(name, self.settings.blocks)}

    def commit(self, path: Path, epochs_done: int) -> None:
        state = {"settings": asdict(self.settings), "epochs_done": epochs_done, "backbone": self.tuned_state(),
                 "heads": self.heads.state_dict(), "optimiser": self.optimiser.state_dict()}
        with atomic_path(path) as tmp:
            self.torch.save(state, tmp)

    def resume(self, path: Path) -> int:
        """The epochs a checkpoint holds (0 without one); refuses one made with other settings."""
        if not path.is_file():
            return 0
        try:
            state = self.torch.load(path, map_location=self.where, weights_only=True)
        except Exception as exc:   # a torn or foreign file: say so rather than train on from garbage
            raise InputError(f"cannot read the fine-tune checkpoint {path} ({exc}); delete it to fine-tune "
                             "from the start") from exc
        if state.get("settings") != asdict(self.settings):
            raise InputError(f"the fine-tune checkpoint {path} was made with {state.get('settings')}, not "
                             f"{asdict(self.settings)}; delete it, or use another --workdir")
        self.backbone.model.load_state_dict(state["backbone"], strict=False)   # copied onto the model's device
        self.heads.load_state_dict(state["heads"])
        self.optimiser.load_state_dict(state["optimiser"])
        return int(state["epochs_done"])


def _is_tuned(name: str, blocks: int) -> bool:
    if name.startswith(("_conv_head.", "_bn1.")):
        return True
    if name.startswith("_blocks."):
        return int(name.split(".")[1]) >= BLOCKS - blocks
    return False


def _augmentation(size: tuple[int, int]):
    """Framing, colour, grey and blur noise on uint8 images; with ``_noisy``'s sensor noise, what the training
    sees instead of the one rendered look of each scene."""
    import torchvision.transforms.v2 as T

    width, height = size
    return T.Compose([T.RandomResizedCrop((height, width), scale=(0.6, 1.0), ratio=(1.2, 1.45), antialias=True),
                      T.RandomApply([T.ColorJitter(0.4, 0.4, 0.4, 0.08)], p=0.9), T.RandomGrayscale(0.15),
                      T.RandomApply([T.GaussianBlur(5, (0.1, 1.5))], p=0.4)])


def save_tuned(backbone: Backbone, folder: Path) -> str:
    """Write a tuned backbone's weights beside the heads; returns the file's name."""
    import torch

    with atomic_path(folder / WEIGHTS_FILE) as tmp:
        torch.save({"blocks": backbone.tuned_blocks, "state": backbone.tuned_state}, tmp)
    return WEIGHTS_FILE
