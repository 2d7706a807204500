"""Replay: a session recorded by ``capture shoot`` (frames + sidecars) or a video file."""
from __future__ import annotations

from pathlib import Path

import cv2

from ..sidecar import read_sidecar
from .base import DeviceDisconnected, DeviceNotFound, ExposureRequest, Frame, FrameSource

VIDEO_SUFFIXES = {".mp4", ".avi", ".mkv", ".mov"}


class ReplaySource(FrameSource):
    def __init__(self, target: str):
        self.path = Path(target)
        self.spec = f"replay:{target}"
        self._frames: list[Path] = []
        self._video = None
        self._index = 0

    def open(self) -> None:
        if not self.path.exists():
            raise DeviceNotFound(f"nothing to replay at {self.path}: give a folder written by 'capture shoot' "
                                 "or a video file")
        if self.path.is_dir():
            self._frames = sorted(self.path.glob("frame_*.png"))
            if not self._frames:
                raise DeviceNotFound(f"{self.path} holds no frame_*.png: not a session written by 'capture shoot'")
        elif self.path.suffix.lower() in VIDEO_SUFFIXES:
            self._video = cv2.VideoCapture(str(self.path))
            if not self._video.isOpened():
                raise DeviceNotFound(f"cannot decode video {self.path}")
        else:
            raise DeviceNotFound(f"{self.path} is neither a session folder nor a video ({', '.join(VIDEO_SUFFIXES)})")

    def set_exposure(self, request: ExposureRequest) -> list[str]:
        # A recording's exposure is what it was; say so rather than pretend.
        return ["replay: exposure settings are ignored; frames keep their recorded exposure"] if (
            request.manual or request.auto) else []

    def read(self) -> Frame:
        if self._video is not None:
            ok, image = self._video.read()
            if not ok:
                raise DeviceDisconnected(f"{self.path}: end of video after {self._index} frames")
            self._index += 1
            h, w = image.shape[:2]
            return Frame(image, {"device": str(self.path), "source": self.spec, "resolution": [w, h],
                                 "frame_index": self._index - 1, "exposure_us": None, "iso": None})
        if self._index >= len(self._frames):
            raise DeviceDisconnected(f"{self.path}: the recording has only {len(self._frames)} frames")
        path = self._frames[self._index]
        self._index += 1
        image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        meta = read_sidecar(path)   # a stand-in stays one when replayed
        meta["replayed_from"] = str(path)
        return Frame(image, meta)

    def close(self) -> None:
        if self._video is not None:
            self._video.release()
            self._video = None
