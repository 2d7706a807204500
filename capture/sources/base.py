"""The frame-source interface and the errors every source reports in the same words."""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from isu_validate.errors import InputError, UserError


class CaptureError(UserError, RuntimeError):
    """A camera problem the user can act on; the message names the problem and the fix."""


class DeviceNotFound(CaptureError):
    pass


class DeviceBusy(CaptureError):
    pass


class PermissionDenied(CaptureError):
    pass


class DeviceDisconnected(CaptureError):
    pass


@dataclass(frozen=True)
class ExposureRequest:
    """Manual exposure (time and ISO/gain) or the camera's automatic exposure."""
    exposure_us: int | None = None
    iso: int | None = None
    auto: bool = False

    def __post_init__(self):
        if self.auto and (self.exposure_us is not None or self.iso is not None):
            raise InputError("choose either --auto-exposure or --exposure-us/--iso, not both")
        if self.exposure_us is not None and self.exposure_us <= 0:
            raise InputError(f"exposure time must be positive, got {self.exposure_us} us")
        if self.iso is not None and self.iso <= 0:
            raise InputError(f"ISO must be positive, got {self.iso}")

    @property
    def manual(self) -> bool:
        return not self.auto and (self.exposure_us is not None or self.iso is not None)


@dataclass
class Frame:
    image: np.ndarray                  # BGR (or grey) uint8
    meta: dict = field(default_factory=dict)  # the sidecar: device, serial, resolution, exposure, ...


class FrameSource(ABC):
    """Open, optionally set exposure, read frames, close.  Usable as a context manager."""
    spec: str = ""

    @abstractmethod
    def open(self) -> None: ...

    @abstractmethod
    def set_exposure(self, request: ExposureRequest) -> list[str]:
        """Apply the request; return warnings where the camera did not take the value asked for."""

    @abstractmethod
    def read(self) -> Frame: ...

    @abstractmethod
    def close(self) -> None: ...

    def __enter__(self):
        self.open()
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def exposure_mismatch(asked: float | None, got: float | None, what: str, unit: str,
                      tolerance: float = 0.05) -> list[str]:
    """A warning when a read-back value is off by more than ``tolerance`` of what was asked."""
    if asked is None:
        return []
    if got is None:
        return [f"the camera does not report its {what}; cannot confirm {asked:g} {unit} was applied"]
    if abs(got - asked) > tolerance * abs(asked):
        return [f"asked for {what} {asked:g} {unit} but the camera reports {got:g} {unit} "
                "(out of range for this sensor mode, or quantised)"]
    return []
