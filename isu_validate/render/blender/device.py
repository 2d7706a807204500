"""Cycles' compute device, through Blender's preferences (inside the worker): the asked GPU type with all
its devices, the denoiser on the GPU where OIDN can run there, or the CPU with one line saying why."""
from __future__ import annotations

import bpy


def select_device(scene, asked: str) -> tuple[str, str | None]:
    """Point ``scene`` at ``asked`` (``cpu`` or a GPU type such as ``optix``); returns the device used and,
    when it is not the one asked, the line the host prints."""
    if asked == "cpu":
        return _cpu(scene), None
    kind = asked.upper()
    prefs = bpy.context.preferences.addons["cycles"].preferences
    try:
        prefs.compute_device_type = kind
    except TypeError:   # the enum of this build lacks it (METAL off macOS)
        return _cpu(scene), fallback_line(asked, f"this Blender build has no {kind} backend")
    prefs.refresh_devices()
    gpus = [d for d in prefs.get_devices_for_type(kind) if d.type == kind]
    if not gpus:
        return _cpu(scene), fallback_line(asked, f"Blender lists no {kind} device")
    for device in prefs.devices:   # the GPUs only: adding the CPU to a GPU render slows it here
        device.use = device.type == kind
    scene.cycles.device = "GPU"
    scene.cycles.denoising_use_gpu = bool(prefs.has_oidn_gpu_devices())
    return asked, None


def fallback_line(asked: str, reason: str) -> str:
    return f"warning: render device {asked} is not available ({reason}); Cycles renders on the CPU"


def _cpu(scene) -> str:
    scene.cycles.device = "CPU"
    scene.cycles.denoising_use_gpu = False
    return "cpu"
