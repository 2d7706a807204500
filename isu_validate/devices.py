"""Where torch work runs: one setting, ``auto|cpu|cuda[:N]|mps``, for every command and the Python API.

``auto`` is the first CUDA device when torch sees one, else the CPU (Apple's ``mps`` only when asked:
its kernels differ enough that a user should choose it). A device that was asked for and is absent
falls back to the CPU with one line on stderr, so a command written for a GPU desk still runs on a
laptop; a spelling that names no device is a user error. What a result was computed on is named by
``describe`` (reports and summaries carry it).

Cycles has its own setting, ``--render-device auto|cpu|optix|cuda|hip|oneapi|metal``: only its spelling
lives here; which devices Blender lists is asked inside the worker (``render/blender/device.py``) and
what ``auto`` means is ``render/gpu.py``'s."""
from __future__ import annotations

import re
import sys
from dataclasses import dataclass

from .errors import InputError

TORCH_DEVICE_CHOICES = "auto|cpu|cuda[:N]|mps"
TORCH_DEVICE_HELP = ("where torch work runs: auto (CUDA when torch sees a GPU, else the CPU), cpu, cuda, cuda:N "
                     "or mps (default auto)")
_SPEC = re.compile(r"^(auto|cpu|mps|cuda(:\d+)?)$")


@dataclass(frozen=True)
class TorchDevice:
    """A resolved device: ``name`` is what torch takes (``cpu``, ``cuda:0``, ``mps``); ``asked`` what the
    user said; ``fallback`` the reason when the asked device was absent and the CPU is used instead."""
    name: str
    asked: str
    fallback: str | None = None

    @property
    def is_cpu(self) -> bool:
        return self.name == "cpu"

    def describe(self) -> str:
        """One phrase for reports: ``cuda:0 (NVIDIA H100)``, ``cpu``, ``cpu (asked cuda: no CUDA device)``."""
        if self.fallback:
            return f"cpu (asked {self.asked}: {self.fallback})"
        if self.name.startswith("cuda"):
            import torch
            return f"{self.name} ({torch.cuda.get_device_name(torch.device(self.name))})"
        return self.name


def check_device_spec(spec: str) -> str:
    """The spelling alone, without importing torch (argparse ``type=``)."""
    text = (spec or "auto").strip().lower()
    if not _SPEC.match(text):
        raise InputError(f"unknown device {spec!r}: use one of {TORCH_DEVICE_CHOICES} (e.g. --device cuda:0)")
    return text


def resolve_torch_device(spec: str | TorchDevice | None = "auto", *, warn=None) -> TorchDevice:
    """Resolve ``spec`` against what torch sees now; an absent device falls back to the CPU with one line."""
    if isinstance(spec, TorchDevice):
        return spec
    text = check_device_spec(spec or "auto")
    import torch
    if text == "auto":
        return _full_float32(torch, TorchDevice("cuda:0" if torch.cuda.is_available() else "cpu", "auto"))
    if text == "cpu":
        return TorchDevice("cpu", "cpu")
    reason = _absent_reason(torch, text)
    if reason is None:
        return _full_float32(torch, TorchDevice("cuda:0" if text == "cuda" else text, text))
    device = TorchDevice("cpu", text, reason)
    (warn or _warn)(f"device {text} is not available ({reason}); torch work runs on the CPU")
    return device


def _full_float32(torch, device: TorchDevice) -> TorchDevice:
    """On CUDA, float32 convolutions and matrix products in full precision: torch lets cuDNN use TF32 by default,
    which moved the reference ISU's features by 0.6% and changed an answer on 1 frame in 64 (H200, 2026-11)."""
    if device.name.startswith("cuda"):
        conv = getattr(torch.backends.cudnn, "conv", None)
        if conv is not None and hasattr(conv, "fp32_precision"):   # torch >= 2.9: the legacy flags must not mix in
            conv.fp32_precision = "ieee"
            torch.backends.cuda.matmul.fp32_precision = "ieee"
        else:
            torch.backends.cudnn.allow_tf32 = False
            torch.backends.cuda.matmul.allow_tf32 = False
    return device


def _absent_reason(torch, text: str) -> str | None:
    if text == "mps":
        mps = getattr(torch.backends, "mps", None)
        return None if mps is not None and mps.is_available() else "this torch has no usable Apple MPS device"
    if not torch.cuda.is_available():
        return "torch sees no CUDA device" + ("" if torch.version.cuda else " (a CPU-only torch build)")
    index = int(text.split(":")[1]) if ":" in text else 0
    count = torch.cuda.device_count()
    return None if index < count else f"cuda:{index} asked, torch sees {count} CUDA device(s)"


def _warn(line: str) -> None:
    print(f"warning: {line}", file=sys.stderr)


RENDER_DEVICES = ("auto", "cpu", "optix", "cuda", "hip", "oneapi", "metal")
RENDER_DEVICE_HELP = ("Cycles' compute device: auto (the CPU unless an NVIDIA GPU this Blender has compiled "
                      "kernels for is present), cpu, optix, cuda, hip, oneapi or metal; an absent device falls "
                      "back to the CPU with one line (default auto)")


def check_render_device(spec: str | None) -> str:
    """A render-device spelling, lower case (argparse ``type=``)."""
    text = (spec or "auto").strip().lower()
    if text not in RENDER_DEVICES:
        raise InputError(f"unknown render device {spec!r}: use one of {'|'.join(RENDER_DEVICES)}")
    return text


def add_render_device_argument(parser) -> None:
    """The one ``--render-device`` flag of every command that renders with Cycles."""
    parser.add_argument("--render-device", default="auto", type=check_render_device,
                        metavar="|".join(RENDER_DEVICES), help=RENDER_DEVICE_HELP)


def add_device_argument(parser) -> None:
    """The one ``--device`` flag of every command that does torch work."""
    parser.add_argument("--device", default="auto", type=check_device_spec, metavar=TORCH_DEVICE_CHOICES,
                        help=TORCH_DEVICE_HELP)
