"""Frame sources: one interface (``FrameSource``), three kinds of camera (V4L2, DepthAI, replay).

``open_source(spec)`` turns a ``--source`` spec into a source:

- ``v4l2:/dev/video0`` or ``v4l2:0``, optionally ``@1280x720``
- ``depthai`` (the first OAK device) or ``depthai:MXID``, optionally ``@1920x1080``
- ``replay:DIR`` (a session recorded by ``capture shoot``) or ``replay:VIDEO.mp4``
- ``standin[:RIG]``: not a camera; with ``--pair``, the pair's scene rendered through another
  rig, light and noise (marked as a stand-in in every sidecar); its command hands it the render
"""
from __future__ import annotations

import re

from isu_validate.errors import InputError

from .base import (CaptureError, DeviceBusy, DeviceDisconnected, DeviceNotFound, ExposureRequest, Frame,
                   FrameSource, PermissionDenied)

__all__ = ["CaptureError", "DeviceBusy", "DeviceDisconnected", "DeviceNotFound", "ExposureRequest", "Frame",
           "FrameSource", "PermissionDenied", "open_source", "parse_spec"]

SPEC_HELP = "v4l2:/dev/videoN[@WxH], depthai[:MXID][@WxH], replay:DIR|VIDEO or standin[:RIG] (with --pair)"


def parse_spec(spec: str) -> tuple[str, str, tuple[int, int] | None]:
    """(kind, target, size) of a source spec."""
    m = re.fullmatch(r"(v4l2|depthai|replay|standin)(?::(.+?))?(?:@(\d+)x(\d+))?", spec.strip())
    if not m:
        raise InputError(f"cannot read source {spec!r}; use {SPEC_HELP}")
    kind, target = m[1], m[2] or ""
    size = (int(m[3]), int(m[4])) if m[3] else None
    if kind in ("v4l2", "replay") and not target:
        raise InputError(f"source {spec!r} needs a target: {SPEC_HELP}")
    return kind, target, size


def open_source(spec: str, render=None) -> FrameSource:
    """``render``: what a stand-in shows (``standin.RenderScene``: the pair's scene, rendered by the
    renderer its command opens); cameras ignore it."""
    kind, target, size = parse_spec(spec)
    if kind == "standin":
        from .standin import StandInSource
        return StandInSource(target, render)
    if kind == "v4l2":
        from .v4l2 import V4L2Source
        return V4L2Source(target, size)
    if kind == "depthai":
        from .oak import DepthAISource
        return DepthAISource(target or None, size)
    from .replay import ReplaySource
    return ReplaySource(target)
