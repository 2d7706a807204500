"""Test double: replays a recorded V4L2 device session through ``cv2.VideoCapture``'s interface.

A device recording (``device.json`` plus frame PNGs) holds what a real camera did: its
control values and ranges (as ``v4l2-ctl --list-ctrls`` reports them), the frames it
delivered, and when it stopped delivering (unplugged).  ``V4L2Source`` runs on it
unchanged, so the source's exposure read-back, warnings and error handling are tested
without hardware.  Layout of ``device.json``:

    {"device": "/dev/video0", "opened": true, "serial": "...",
     "props": {"CAP_PROP_EXPOSURE": 156, "CAP_PROP_AUTO_EXPOSURE": 3, ...},
     "ranges": {"CAP_PROP_EXPOSURE": [3, 2047], ...},      # set() clamps, as the driver does
     "frames": ["frame_0000.png", ...], "disconnect_after": null}
"""
from __future__ import annotations

import json
from pathlib import Path

import cv2


class RecordedCapture:
    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        rec = json.loads((self.folder / "device.json").read_text())
        self.opened = bool(rec.get("opened", True))
        self.serial = rec.get("serial")
        self.props = {getattr(cv2, k): float(v) for k, v in rec.get("props", {}).items()}
        self.ranges = {getattr(cv2, k): tuple(v) for k, v in rec.get("ranges", {}).items()}
        self.frames = list(rec.get("frames", []))
        self.disconnect_after = rec.get("disconnect_after")
        self.reads = 0

    def isOpened(self) -> bool:  # noqa: N802 (OpenCV's name)
        return self.opened

    def set(self, prop, value) -> bool:
        if prop not in self.props and prop not in self.ranges:
            return False
        lo, hi = self.ranges.get(prop, (-float("inf"), float("inf")))
        self.props[prop] = float(min(max(value, lo), hi))
        return True

    def get(self, prop) -> float:
        return self.props.get(prop, -1.0)

    def read(self):
        if not self.frames or (self.disconnect_after is not None and self.reads >= self.disconnect_after):
            return False, None
        img = cv2.imread(str(self.folder / self.frames[self.reads % len(self.frames)]), cv2.IMREAD_COLOR)
        self.reads += 1
        self.props[cv2.CAP_PROP_POS_MSEC] = self.reads * 33.3
        return img is not None, img

    def release(self) -> None:
        self.opened = False


class RecordedImgFrame:
    """One ``depthai.ImgFrame``'s metadata, replayed from a recording (``frames.json``).

    depthai's ImgFrame offers no setters for exposure or ISO, so a recording keeps the
    values its getters returned; ``oak.frame_meta`` reads them through the same getters.
    """

    def __init__(self, rec: dict):
        self.rec = rec

    def getExposureTime(self):  # noqa: N802 (depthai's names)
        import datetime
        return datetime.timedelta(microseconds=self.rec["exposure_us"])

    def getSensitivity(self):  # noqa: N802
        return self.rec["iso"]

    def getLensPosition(self):  # noqa: N802
        return self.rec["lens_position"]

    def getColorTemperature(self):  # noqa: N802
        return self.rec["color_temperature"]

    def getSequenceNum(self):  # noqa: N802
        return self.rec["sequence"]

    def getTimestamp(self):  # noqa: N802
        import datetime
        return datetime.timedelta(seconds=self.rec["timestamp_s"])

    def getWidth(self):  # noqa: N802
        return self.rec["width"]

    def getHeight(self):  # noqa: N802
        return self.rec["height"]


def load_depthai_recording(folder: str | Path) -> tuple[str, list[RecordedImgFrame]]:
    rec = json.loads((Path(folder) / "frames.json").read_text())
    return rec["device_id"], [RecordedImgFrame(f) for f in rec["frames"]]
