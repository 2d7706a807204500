"""What ``--render-device auto`` means, decided on the host before a worker starts (so the render cache
key knows the device): the CPU, unless an NVIDIA GPU is present whose architecture this Blender ships a
compiled CUDA kernel (a cubin) for; then ``cuda``.

Why so narrow: Blender 5.2.3's bpy ships cubins for a few architectures (sm_50..sm_86, sm_120) and PTX
for the rest. On an H200 (sm_90) compiling that PTX took 400 s of CPU (CUDA 13.0's ``ptxas``; the driver
does the same work on the first frame, then keeps it in its compute cache); what the GPU then gains is in
docs/SETUP.md, "GPUs". A first frame that silently takes minutes is no default, so ``auto`` stays on the CPU
there; a GPU asked for by name gets that first frame's time (``first_frame_compiles``). A cubin placed
beside bpy's own counts as shipped. OptiX's kernels are PTX only, so ``auto`` never picks it; HIP, oneAPI
and Metal were never tried here, so they are asked for by name."""
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


# the longest a first GPU frame may take while the driver compiles Cycles' kernels (400 s measured, on 16 cores)
FIRST_FRAME_COMPILE_S = 1800.0


def first_frame_compiles(device: str) -> str | None:
    """The line to print before a first frame on ``device`` that must first compile Cycles' GPU kernels
    (its architecture has no shipped cubin, or OptiX), or None: that frame may take minutes, once."""
    if device == "optix":
        return ("note: OptiX compiles Cycles' kernels on the first frame (minutes, once; the driver keeps them); "
                f"allowing it up to {FIRST_FRAME_COMPILE_S:.0f} s")
    if device != "cuda":
        return None
    shipped = shipped_cubins()
    missing = [cap for cap in nvidia_compute_caps() if cap not in shipped]
    if not missing:
        return None
    return (f"note: this Blender ships no CUDA kernel for sm_{missing[0]}: the first frame compiles it from PTX "
            f"(about 7 minutes on an H200's CPU, once; the driver keeps it); allowing it up to "
            f"{FIRST_FRAME_COMPILE_S:.0f} s (docs/SETUP.md says how to compile it ahead with ptxas)")


def device_identity(device: str) -> list:
    """What the device adds to the render cache key: nothing for the CPU (its caches stay valid); the type
    for a GPU, whose pixels differ from the CPU's by float rounding (PSNR 61 dB on an H200): a run's frames
    must come from one device to be reproduced bit for bit."""
    return [] if device == "cpu" else [f"render-device:{device}"]
