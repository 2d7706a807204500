"""What ``--render-device auto`` means, decided on the host before a worker starts (so the render cache
key knows the device): the CPU, unless an NVIDIA GPU is present whose architecture this Blender ships a
compiled CUDA kernel (a cubin) for; then ``cuda``.

Why so narrow: Blender 5.2.3's bpy ships cubins for a few architectures (sm_50..sm_86, sm_120) and PTX
for the rest; on an H100 (sm_90) a probe scene gave no frame within 120 s with CUDA nor 235 s with OptiX
(the driver compiling PTX, most likely) where 16 CPU cores took 0.7 s. OptiX's kernels are PTX only, so
``auto`` never picks it; HIP, oneAPI and Metal were never tried here, so they are asked for by name."""
from __future__ import annotations

import importlib.util
import re
import subprocess
from pathlib import Path

GPU_TYPES = ("optix", "cuda", "hip", "oneapi", "metal")


def resolve_render_device(spec: str) -> str:
    """``auto`` -> ``cuda`` or ``cpu``; any other spelling as it is (the worker falls back if absent)."""
    if spec != "auto":
        return spec
    shipped = shipped_cubins()
    return "cuda" if any(cap in shipped for cap in nvidia_compute_caps()) else "cpu"


def shipped_cubins() -> set[str]:
    """The architectures (``"86"``, ``"120"``) bpy ships compiled CUDA kernels for; read from its files,
    without importing bpy (only the worker does)."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        return set()
    root = Path(next(iter(spec.submodule_search_locations)))
    return {m.group(1) for f in root.glob("*/scripts/addons_core/cycles/lib/kernel_sm_*.cubin*")
            if (m := re.match(r"kernel_sm_(\d+)\.cubin", f.name))}


def nvidia_compute_caps() -> list[str]:
    """Compute capabilities of the NVIDIA GPUs ``nvidia-smi`` lists (``"90"`` for 9.0); none without it."""
    try:
        out = subprocess.run(["nvidia-smi", "--query-gpu=compute_cap", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=20, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return []
    return [line.strip().replace(".", "") for line in out.splitlines() if re.fullmatch(r"\d+\.\d+", line.strip())]


def device_identity(device: str) -> list:
    """What the device adds to the render cache key: nothing for the CPU (its caches stay valid); the type
    for a GPU, whose pixels were never compared with the CPU's here (no GPU was available to measure)."""
    return [] if device == "cpu" else [f"render-device:{device}"]
