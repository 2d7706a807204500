"""One strength of a ``--camera-jitter`` or ``--sensor-effects`` option: a number between 0 and its limit, or a
one-line error naming the option, the item and the range."""
from __future__ import annotations

from ..errors import InputError


def strength(option: str, text: str, key: str, value: str, limit: float, meaning: str) -> float:
    try:
        number = float(value)
    except ValueError:
        raise InputError(f"{option} {text!r}: {key}={value!r} is not a number") from None
    if not 0.0 <= number <= limit:
        raise InputError(f"{option} {text!r}: {key} must be between 0 and {limit:g} ({meaning})")
    return number
