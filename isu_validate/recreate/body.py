"""The driver's weight for the rendered height: a weight class is a BMI band, so its kilograms depend on
the stature; the sheet gives them at the stature the render used for the scene's height class
(``render/people/phenotype.py``: each class renders at its band's centre), not across every height."""
from __future__ import annotations

from ..render.people.phenotype import BMI_BANDS, BMI_TARGET, HEIGHT_BANDS, WEIGHT_WORDS


def rendered_stature(height_class: str) -> float | None:
    band = HEIGHT_BANDS.get(str(height_class))
    return sum(band) / 2 if band else None


def weight_at_height(weight_class: str, height_class: str) -> str | None:
    """E.g. "average build, BMI 21-25: 72-86 kg at 1.85 m (the rendered body 79 kg)"; None for classes
    the renderer does not know."""
    stature = rendered_stature(height_class)
    band = BMI_BANDS.get(str(weight_class))
    if stature is None or band is None:
        return None
    low, high = (bmi * stature ** 2 for bmi in band)
    body = BMI_TARGET[str(weight_class)] * stature ** 2
    return (f"{WEIGHT_WORDS[str(weight_class)]}, BMI {band[0]:g}-{band[1]:g}: {low:.0f}-{high:.0f} kg at "
            f"{stature:.2f} m (the rendered body {body:.0f} kg)")
