"""Facial expressions as anny's ARKit-style facial actions (0..1).

HAPPY is a broad smile (Duchenne: cheeks raised, eyes narrowed, lips parted over the teeth); SERIOUS a
stern face (brows lowered and drawn, lips pressed), never a sad one. How strong they must be to read at the presets'
resolutions was measured (see ``isu-validate bench faces`` and the render README)."""
from __future__ import annotations

# anny's resting eyelids leave a narrow opening that, seen from above by the mirror, hides the whites and
# most of the iris: every expression opens the eyes a little (eyeWide), as an alert driver's are
_OPEN_EYES = {"eyeWideLeft": 0.3, "eyeWideRight": 0.3}
EXPRESSIONS = {
    # Duchenne smile, laughing: mouth corners up and back, lips parted over the teeth, cheeks raised. Seen
    # from the mirror the face is foreshortened from above: a closed-lip smile (jaw 0.12, upper lip 0.5) read
    # happy to a photo-trained model in 7 of 16 frames, this one in 30 of 48 (three seeds); narrowing the
    # eyes as far as a laugh does (eyeSquint 0.45) hid them from the face detector in 4 of 64 frames
    "HAPPY": {"mouthSmileLeft": 1.0, "mouthSmileRight": 1.0, "cheekSquintLeft": 0.7, "cheekSquintRight": 0.7,
              "eyeSquintLeft": 0.15, "eyeSquintRight": 0.15, "eyeWideLeft": 0.15, "eyeWideRight": 0.15,
              "jawOpen": 0.25, "mouthUpperUpLeft": 0.7, "mouthUpperUpRight": 0.7, "mouthLowerDownLeft": 0.3,
              "mouthLowerDownRight": 0.3, "mouthDimpleLeft": 0.3, "mouthDimpleRight": 0.3,
              "mouthStretchLeft": 0.2, "mouthStretchRight": 0.2},
    # stern, not sad: brows lowered and drawn in, lips pressed flat, the gaze steady; no frown and no
    # raised inner brows (those read as sadness)
    "SERIOUS": {"browDownLeft": 0.75, "browDownRight": 0.75, "mouthPressLeft": 0.6, "mouthPressRight": 0.6,
                "mouthRollLower": 0.1, "jawForward": 0.1, "noseSneerLeft": 0.1, "noseSneerRight": 0.1,
                **_OPEN_EYES},
    "NEUTRAL": _OPEN_EYES,
}


def facial_actions(expression: str, strength: float = 1.0) -> dict[str, float]:
    if expression not in EXPRESSIONS:
        raise ValueError(f"unknown expression {expression!r}; known: {', '.join(EXPRESSIONS)}")
    return {k: min(1.0, v * strength) for k, v in EXPRESSIONS[expression].items()}
