"""Style-transferred copies of a dataset's renders (``--style IMG...``): the sim-to-real augmentation.

Each style image gives every render one copy (labels and masks shared). A style whose fast net is given
(``--style-model``, a model of ``stylize train``, matched to its style image by the image's SHA-256) goes
through that net (one forward pass); any other through Gatys' optimisation (``style_transfer.gatys``,
VGG19, ``style_steps`` L-BFGS iterations at ``style_size`` px, written back at the render's size). Both
are ``style_transfer``'s own functions, as ``isu-validate stylize`` calls them.
"""
from __future__ import annotations

import hashlib
import time
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Sequence

from ..errors import InputError, InputNotFound


@dataclass(frozen=True)
class StyleSpec:
    image: str                 # the style image (absolute path)
    sha256: str
    method: str                # "fast" | "gatys"
    model: str | None = None   # the fast net
    size: int = 192            # gatys: longer side optimised
    steps: int = 40            # gatys: L-BFGS iterations

    def to_dict(self) -> dict:
        return asdict(self)


def plan_styles(images: Sequence[str], models: Sequence[str], size: int, steps: int) -> list[StyleSpec]:
    """Check every style image decodes and every model belongs to one of them (before any render)."""
    if not images:
        return []
    from style_transfer.imageio import unreadable

    digests = []
    for image in images:
        if not Path(image).is_file():
            raise InputNotFound(f"style image {image} does not exist")
        if reason := unreadable(image):
            raise InputError(f"style image {image} does not decode ({reason}); give a PNG or JPEG photo")
        digests.append(hashlib.sha256(Path(image).read_bytes()).hexdigest())
    fast = {}
    for model in models:
        trained_for = _model_style(model)
        if trained_for not in digests:
            raise InputError(f"style model {model} was trained for another style image than those given with "
                             "--style; give its style image too, or drop the model")
        fast[trained_for] = model
    return [StyleSpec(str(image), sha, "fast" if sha in fast else "gatys", fast.get(sha), size, steps)
            for image, sha in zip(images, digests)]


def _model_style(model: str) -> str:
    from style_transfer import load_model

    _, meta = load_model(Path(model))
    return str(meta.get("style_sha256", ""))


class Stylist:
    """The style transfers of one worker process: VGG19 and the nets loaded once."""

    def __init__(self, specs: Sequence[StyleSpec], threads: int, device: str = "auto"):
        import torch

        from style_transfer.imageio import load_image

        from ..devices import resolve_torch_device

        torch.set_num_threads(max(1, threads))
        self.device = resolve_torch_device(device)   # where VGG and the nets run
        self.specs = list(specs)
        self._vgg = None
        self._style_images = {}
        self._nets = {}
        for spec in self.specs:
            if spec.method == "fast":
                from style_transfer import load_model
                self._nets[spec.image] = load_model(Path(spec.model))[0].to(self.device.name)
            else:
                self._style_images[spec.image] = load_image(spec.image, spec.size)

    def stylise(self, k: int, source: Path, target: Path, seed: int) -> float:
        """Write the copy of ``source`` in style ``k`` (0-based) to ``target``; the seconds it took."""
        from style_transfer.imageio import load_image, save_image

        start = time.perf_counter()
        spec = self.specs[k]
        noise_seed = seed + zlib.crc32(source.name.encode())   # reproducible, not one pattern for all
        if spec.method == "fast":
            from style_transfer import stylize_fast
            save_image(stylize_fast(self._nets[spec.image], load_image(source), noise_seed), target)
        else:
            from PIL import Image
            from style_transfer import GatysConfig, stylize_gatys

            with Image.open(source) as img:
                size = img.size
            config = GatysConfig(steps=spec.steps, size=spec.size, seed=noise_seed)
            result = stylize_gatys(load_image(source, spec.size), self._style_images[spec.image], config, self.vgg)
            save_image(result.image, target, size=size)
        return time.perf_counter() - start

    @property
    def vgg(self):
        if self._vgg is None:
            from style_transfer import VGG19
            self._vgg = VGG19("avg").to(self.device.name)
        return self._vgg
