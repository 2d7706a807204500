"""Facial expressions as anny's ARKit-style facial actions (0..1).

HAPPY is a broad smile (Duchenne: cheeks raised, eyes narrowed, lips parted); SERIOUS a stern face
(brows lowered and drawn, lips pressed, corners down). How strong they must be to read at the presets'
resolutions was measured (see ``isu-validate bench faces`` and the render README)."""
from __future__ import annotations

EXPRESSIONS = {
    "HAPPY": {"mouthSmileLeft": 1.0, "mouthSmileRight": 1.0, "cheekSquintLeft": 0.7, "cheekSquintRight": 0.7,
              "eyeSquintLeft": 0.4, "eyeSquintRight": 0.4, "jawOpen": 0.18, "mouthUpperUpLeft": 0.45,
              "mouthUpperUpRight": 0.45, "mouthDimpleLeft": 0.4, "mouthDimpleRight": 0.4,
              "browInnerUp": 0.15},
    "SERIOUS": {"browDownLeft": 0.8, "browDownRight": 0.8, "mouthPressLeft": 0.7, "mouthPressRight": 0.7,
                "mouthFrownLeft": 0.6, "mouthFrownRight": 0.6, "mouthRollLower": 0.2, "eyeSquintLeft": 0.15,
                "eyeSquintRight": 0.15, "noseSneerLeft": 0.1, "noseSneerRight": 0.1},
    "NEUTRAL": {},
}


def facial_actions(expression: str, strength: float = 1.0) -> dict[str, float]:
    if expression not in EXPRESSIONS:
        raise ValueError(f"unknown expression {expression!r}; known: {', '.join(EXPRESSIONS)}")
    return {k: min(1.0, v * strength) for k, v in EXPRESSIONS[expression].items()}
