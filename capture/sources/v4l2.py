"""V4L2 cameras (USB webcams, most in-cabin cameras on Linux) through OpenCV's CAP_V4L2.

Exposure: CAP_PROP_AUTO_EXPOSURE takes the raw V4L2 menu value (1 manual, 3 aperture
priority) and CAP_PROP_EXPOSURE is ``exposure_time_absolute`` in 100 us units.  V4L2 has
no ISO: ``--iso`` is written to the gain control as is, and reported as gain.
"""
from __future__ import annotations

import datetime as _dt
import errno
import os
from pathlib import Path

import cv2

from .base import (DeviceBusy, DeviceDisconnected, DeviceNotFound, ExposureRequest, Frame, FrameSource,
                   PermissionDenied, exposure_mismatch)

AUTO_MANUAL, AUTO_APERTURE_PRIORITY = 1, 3


def device_path(target: str) -> str:
    return f"/dev/video{target}" if target.isdigit() else target


class V4L2Source(FrameSource):
    def __init__(self, target: str, size=None, capture_factory=None, serial: str | None = None):
        self.path = device_path(target)
        self.spec = f"v4l2:{self.path}"
        self.size = size
        # The factory is cv2.VideoCapture; a recorded device session replays through the same calls.
        self._factory = capture_factory or (lambda path: cv2.VideoCapture(path, cv2.CAP_V4L2))
        self._real_device = capture_factory is None  # file checks only make sense for a real /dev node
        self._serial = serial
        self.cap = None
        self.frames_read = 0

    def open(self) -> None:
        if self._real_device and not Path(self.path).exists():
            raise DeviceNotFound(f"{self.path} does not exist: is the camera plugged in? "
                                 "'isu-validate capture list' shows the cameras found")
        if self._real_device and not os.access(self.path, os.R_OK | os.W_OK):
            raise PermissionDenied(f"no permission to open {self.path}: add your user to the 'video' group "
                                   "(sudo usermod -aG video $USER, then log in again)")
        self.cap = self._factory(self.path)
        if not self.cap.isOpened():
            raise DeviceBusy(f"could not open {self.path}: another program may be using it (check with "
                             f"'fuser {self.path}'), or it is not a capture device")
        if self.size:
            self.cap.set(cv2.CAP_PROP_FRAME_WIDTH, self.size[0])
            self.cap.set(cv2.CAP_PROP_FRAME_HEIGHT, self.size[1])

    def set_exposure(self, request: ExposureRequest) -> list[str]:
        cap = self._need_open()
        if request.auto:
            cap.set(cv2.CAP_PROP_AUTO_EXPOSURE, AUTO_APERTURE_PRIORITY)
            return []
        if not request.manual:
            return []
        cap.set(cv2.CAP_PROP_AUTO_EXPOSURE, AUTO_MANUAL)
        warnings = []
        if request.exposure_us is not None:
            cap.set(cv2.CAP_PROP_EXPOSURE, request.exposure_us / 100.0)
            warnings += exposure_mismatch(request.exposure_us, self._exposure_us(), "exposure time", "us")
        if request.iso is not None:
            cap.set(cv2.CAP_PROP_GAIN, request.iso)
            warnings += exposure_mismatch(request.iso, self._prop(cv2.CAP_PROP_GAIN), "gain", "(raw)")
        if self._prop(cv2.CAP_PROP_AUTO_EXPOSURE) not in (None, AUTO_MANUAL):
            warnings.append("the camera stayed in automatic exposure: it may not support manual exposure")
        return warnings

    def read(self) -> Frame:
        cap = self._need_open()
        ok, image = cap.read()
        if not ok or image is None:
            raise DeviceDisconnected(f"{self.path} stopped delivering frames after {self.frames_read}: "
                                     "was it unplugged? Reconnect it and shoot again")
        self.frames_read += 1
        h, w = image.shape[:2]
        meta = {"device": self.path, "source": self.spec, "serial": self._serial or _serial_of(self.path),
                "resolution": [w, h], "exposure_us": self._exposure_us(),
                "auto_exposure": self._prop(cv2.CAP_PROP_AUTO_EXPOSURE) != AUTO_MANUAL,
                "iso": None, "gain": self._prop(cv2.CAP_PROP_GAIN),
                "lens_position": self._prop(cv2.CAP_PROP_FOCUS),
                "white_balance_k": self._prop(cv2.CAP_PROP_WB_TEMPERATURE),
                "timestamp": _dt.datetime.now(_dt.timezone.utc).isoformat(),
                "device_timestamp_ms": self._prop(cv2.CAP_PROP_POS_MSEC)}
        return Frame(image, meta)

    def close(self) -> None:
        if self.cap is not None:
            self.cap.release()
            self.cap = None

    def _need_open(self):
        if self.cap is None:
            raise RuntimeError("open the source first")
        return self.cap

    def _prop(self, prop):
        value = self.cap.get(prop)
        return None if value is None or value == -1 else float(value)  # OpenCV's "not supported" is -1

    def _exposure_us(self):
        v = self._prop(cv2.CAP_PROP_EXPOSURE)
        return None if v is None else v * 100.0


def _serial_of(path: str) -> str | None:
    """The USB serial number from sysfs, when the kernel exposes one."""
    name = Path(path).name
    for up in ("device/../serial", "device/../../serial"):
        p = Path("/sys/class/video4linux") / name / up
        try:
            return p.read_text().strip()
        except OSError as exc:
            if exc.errno not in (errno.ENOENT, errno.ENOTDIR, errno.EACCES):
                raise
    return None
