"""Luxonis DepthAI (OAK) cameras through the depthai v3 API.

Manual exposure goes in as the camera node's initial control (so the very first frame
has it) and is confirmed from each frame's own metadata (``getExposureTime``,
``getSensitivity``), which is what the sensor actually used.
"""
from __future__ import annotations

import datetime as _dt
import time

from .base import (CaptureError, DeviceBusy, DeviceDisconnected, DeviceNotFound, ExposureRequest, Frame,
                   FrameSource, PermissionDenied, exposure_mismatch)

DEFAULT_SIZE = (1920, 1080)
READ_TIMEOUT_S = 5.0


def _dai():
    import depthai as dai  # imported late: it prints USB warnings at import on machines without USB access
    return dai


class DepthAISource(FrameSource):
    def __init__(self, device_id: str | None = None, size=None):
        self.device_id = device_id
        self.size = size or DEFAULT_SIZE
        self.spec = f"depthai:{device_id}" if device_id else "depthai"
        self.pipeline = self.device = self.queue = self.control = None
        self._request = ExposureRequest()
        self.frames_read = 0

    def open(self) -> None:
        dai = _dai()
        infos = dai.Device.getAllAvailableDevices()
        if self.device_id:
            infos = [i for i in infos if i.getDeviceId() == self.device_id or i.name == self.device_id]
        if not infos:
            raise DeviceNotFound(_not_found_message(self.device_id))
        try:
            self.device = dai.Device(infos[0])
        except RuntimeError as exc:
            raise _classify(exc, infos[0].getDeviceId()) from None
        self.pipeline = dai.Pipeline(self.device)
        cam = self.pipeline.create(dai.node.Camera).build(dai.CameraBoardSocket.CAM_A)
        self._cam = cam
        self.queue = cam.requestOutput(tuple(self.size), dai.ImgFrame.Type.NV12).createOutputQueue()
        self.control = cam.inputControl.createInputQueue()
        self._started = False

    def set_exposure(self, request: ExposureRequest) -> list[str]:
        dai = _dai()
        self._request = request
        if not (request.auto or request.manual):
            return []
        # Before the pipeline starts the initial control applies from the first frame on;
        # afterwards a runtime control message takes a few frames to reach the sensor.
        ctrl = self._cam.initialControl if not self._started else dai.CameraControl()
        if request.auto:
            ctrl.setAutoExposureEnable()
        else:
            ctrl.setManualExposure(int(request.exposure_us or 10000), int(request.iso or 100))
        if self._started:
            self.control.send(ctrl)
        return []  # confirmed per frame, from the frame's own metadata (see read)

    def read(self) -> Frame:
        if not self._started:
            self.pipeline.start()
            self._started = True
        deadline = time.monotonic() + READ_TIMEOUT_S
        try:
            msg = None
            while msg is None:
                if not self.pipeline.isRunning():
                    raise DeviceDisconnected(f"{self.spec}: the device stopped (unplugged?) after "
                                             f"{self.frames_read} frames; reconnect it and shoot again")
                msg = self.queue.tryGet()
                if msg is None:
                    if time.monotonic() > deadline:
                        raise DeviceDisconnected(f"{self.spec}: no frame for {READ_TIMEOUT_S:g} s after "
                                                 f"{self.frames_read} frames: is the cable loose?")
                    time.sleep(0.005)
        except RuntimeError as exc:
            if isinstance(exc, CaptureError):
                raise
            raise DeviceDisconnected(f"{self.spec}: lost the device after {self.frames_read} frames ({exc})") from None
        self.frames_read += 1
        meta = frame_meta(msg, self.device.getDeviceId(), self.spec, self._request)
        return Frame(msg.getCvFrame(), meta)

    def close(self) -> None:
        if self.pipeline is not None and getattr(self, "_started", False):
            self.pipeline.stop()
        if self.device is not None:
            self.device.close()
        self.pipeline = self.device = None


def frame_meta(msg, serial: str, spec: str, request: ExposureRequest) -> dict:
    """The sidecar of one ImgFrame, with a warning when it did not get the exposure asked for."""
    exposure_us = msg.getExposureTime().total_seconds() * 1e6
    iso = msg.getSensitivity()
    warnings = []
    if request.manual:
        warnings += exposure_mismatch(request.exposure_us, exposure_us, "exposure time", "us")
        warnings += exposure_mismatch(request.iso, iso, "ISO", "")
    meta = {"device": "depthai", "source": spec, "serial": serial,
            "resolution": [msg.getWidth(), msg.getHeight()], "exposure_us": exposure_us, "iso": iso,
            "gain": None, "auto_exposure": not request.manual, "lens_position": msg.getLensPosition(),
            "white_balance_k": msg.getColorTemperature(), "sequence": msg.getSequenceNum(),
            "timestamp": _dt.datetime.now(_dt.timezone.utc).isoformat(),
            "device_timestamp_s": msg.getTimestamp().total_seconds()}
    if warnings:
        meta["warnings"] = warnings
    return meta


def _not_found_message(device_id) -> str:
    which = f"DepthAI device {device_id}" if device_id else "no DepthAI device"
    return (f"{which} found: check the USB cable (USB3 port, powered hub for OAK-D), and on Linux the udev rule "
            "for vendor 03e7 (echo 'SUBSYSTEM==\"usb\", ATTRS{idVendor}==\"03e7\", MODE=\"0666\"' | "
            "sudo tee /etc/udev/rules.d/80-movidius.rules; "
            "sudo udevadm control --reload-rules && sudo udevadm trigger)")


def _classify(exc: RuntimeError, device_id: str) -> CaptureError:
    text = str(exc).lower()
    if "permission" in text or "insufficient" in text:
        return PermissionDenied(f"no permission to open DepthAI device {device_id}: install the udev rule for "
                                "vendor 03e7 (see 'isu-validate capture list')")
    if "busy" in text or "already" in text or "in use" in text:
        return DeviceBusy(f"DepthAI device {device_id} is in use by another program; close it and retry")
    return DeviceNotFound(f"could not open DepthAI device {device_id}: {exc}")
