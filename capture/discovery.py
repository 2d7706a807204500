"""``capture list``: every camera this machine can see, and why one might be invisible.

Three independent looks: V4L2 device nodes (with formats and sizes through linuxpy),
DepthAI's own discovery, and raw USB devices with Luxonis' vendor id (0x03E7) through
pyusb, which finds an OAK even when depthai cannot open it (permissions, bootloader).
"""
from __future__ import annotations

import glob
import os

LUXONIS_VENDOR_ID = 0x03E7
# why each look may come back empty: reported (text and JSON alike) when no camera at all was found
NOT_FOUND = {
    "v4l2": "no /dev/video* devices (is a USB camera plugged in? in a container, pass --device /dev/videoN)",
    "depthai": ("no DepthAI devices (USB3 cable; udev rule for vendor 03e7; in a container "
                "-v /dev/bus/usb:/dev/bus/usb)"),
    "usb": "no USB devices with Luxonis vendor id 03e7",
}


def list_v4l2() -> list[dict]:
    found = []
    for path in sorted(glob.glob("/dev/video*"), key=lambda p: (len(p), p)):
        entry = {"kind": "v4l2", "path": path, "spec": f"v4l2:{path}"}
        if not os.access(path, os.R_OK | os.W_OK):
            entry["error"] = "permission denied: add your user to the 'video' group (sudo usermod -aG video $USER)"
        else:
            entry.update(_v4l2_details(path))
        found.append(entry)
    return found


def _v4l2_details(path: str) -> dict:
    try:
        from linuxpy.video.device import BufferType, Device
        with Device(path) as dev:
            info = dev.info
            capture = any(f.type == BufferType.VIDEO_CAPTURE for f in info.formats)
            formats: dict[str, set] = {}
            for ft in info.frame_types if capture else []:
                formats.setdefault(ft.pixel_format.name, set()).add((ft.width, ft.height))
            return {"name": info.card, "driver": info.driver, "bus": info.bus_info, "capture": capture,
                    "formats": {k: [f"{w}x{h}" for w, h in sorted(v)] for k, v in formats.items()}}
    except PermissionError:
        return {"error": "permission denied: add your user to the 'video' group"}
    except OSError as exc:
        busy = getattr(exc, "errno", None) == 16
        return {"error": "busy: another program is using it" if busy else f"cannot query: {exc}"}


def list_depthai() -> tuple[list[dict], str | None]:
    try:
        import depthai as dai
    except ImportError as exc:
        return [], f"depthai not importable: {exc}"
    found = []
    for info in dai.Device.getAllAvailableDevices():
        found.append({"kind": "depthai", "id": info.getDeviceId(), "name": info.name, "state": str(info.state),
                      "protocol": str(info.protocol), "spec": f"depthai:{info.getDeviceId()}",
                      "formats": {"NV12": ["1920x1080", "1280x720", "640x480"]}})
    return found, None


def list_luxonis_usb() -> tuple[list[dict], str | None]:
    try:
        import libusb_package
        import usb.core
    except ImportError as exc:
        return [], f"pyusb/libusb-package not importable: {exc}"
    try:
        backend = libusb_package.get_libusb1_backend()
        devices = list(usb.core.find(find_all=True, idVendor=LUXONIS_VENDOR_ID, backend=backend))
    except usb.core.NoBackendError:
        return [], "no libusb backend: reinstall libusb-package"
    except usb.core.USBError as exc:
        return [], f"USB enumeration failed: {exc}"
    return [{"kind": "usb", "vendor": f"{d.idVendor:04x}", "product": f"{d.idProduct:04x}", "bus": d.bus,
             "address": d.address,
             # 2485: Movidius MyriadX in USB boot mode (no firmware yet); f63b: running OAK
             "note": "booted OAK" if d.idProduct == 0xF63B else "OAK in USB boot mode"} for d in devices], None


def list_cameras() -> dict:
    """Every camera found, and ``problems``: what to check, the same list text and JSON output show."""
    depthai, depthai_problem = list_depthai()
    usb, usb_problem = list_luxonis_usb()
    found = {"v4l2": list_v4l2(), "depthai": depthai, "usb": usb}
    problems = [] if any_camera(found) else list(NOT_FOUND.values())
    found["problems"] = problems + [p for p in (depthai_problem, usb_problem) if p]
    return found


def any_camera(found: dict) -> bool:
    return any(found.get(kind) for kind in NOT_FOUND)


def none_found_message(found: dict) -> str:
    return "\n".join(["no cameras found:"] + [f"- {p}" for p in found.get("problems", [])])
