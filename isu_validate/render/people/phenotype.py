"""Who the people are: the scene's driver classes (gender, height class H1-H4, weight class W1-W4) and
the child, mapped to anny's phenotype inputs.

Height and weight classes are real anthropometric ranges a lab technician can pick a person by:
stature bands of 10 cm (H1 1.50-1.60 m ... H4 1.80-1.90 m) and body-mass-index bands (W1 slim, BMI
under 21; W2 21-25; W3 25-30; W4 30 and over). Each class renders one body at the band's centre
(stature 1.55/1.65/1.75/1.85 m; BMI 19/23/27.5/32), for either gender. anny has no stature or mass
input, so its inputs were calibrated against ``anny.Anthropometry`` (stature = rest-pose height, mass
= mesh volume x 980 kg/m3) by bisection: ``python -m isu_validate.render.people.phenotype`` reruns
the calibration and prints the table below and the technician texts of the space file; a test
checks that the table still lands on the targets."""
from __future__ import annotations

from dataclasses import dataclass

HEIGHT_BANDS = {"H1": (1.50, 1.60), "H2": (1.60, 1.70), "H3": (1.70, 1.80), "H4": (1.80, 1.90)}
BMI_BANDS = {"W1": (17.0, 21.0), "W2": (21.0, 25.0), "W3": (25.0, 30.0), "W4": (30.0, 35.0)}
BMI_TARGET = {"W1": 19.0, "W2": 23.0, "W3": 27.5, "W4": 32.0}
WEIGHT_WORDS = {"W1": "slim", "W2": "average build", "W3": "overweight", "W4": "obese"}
GENDER = {"MALE": 0.0, "FEMALE": 1.0}
ADULT_AGE = 0.792          # anny's age input for 35 years (MorphologicalAgeMapping)
# children (anny.shape_distribution.MorphologicalAgeMapping): 1 year -> 0.05 (0.78 m, 7.3 kg),
# 2.5 years -> 0.1325 (0.93 m)
CHILD_AGE = {"REAR_FACING": 0.05, "FRONT_FACING": 0.1325}
PROPORTIONS = 0.5

# anny's weight and muscle inputs interact (little muscle at maximal weight is obese, at minimal weight
# frail), so the build follows one path through them, monotone in BMI:
# s = 0 (weight 0, muscle 0) -> 1 (0, 0.5) -> 2 (1, 0.5) -> 3 (1, 0)
_BUILD_PATH = ((0.0, 0.0), (0.0, 0.5), (1.0, 0.5), (1.0, 0.0))

# calibrated: (gender, height class) -> anny height input; (gender, height, weight class) -> build s
HEIGHT_INPUT = {
    ('MALE', 'H1'): 0.1815, ('MALE', 'H2'): 0.2734, ('MALE', 'H3'): 0.3652, ('MALE', 'H4'): 0.4569,
    ('FEMALE', 'H1'): 0.3038, ('FEMALE', 'H2'): 0.3956, ('FEMALE', 'H3'): 0.4873, ('FEMALE', 'H4'): 0.5791,
}
BUILD_INPUT = {
    ('MALE', 'H1', 'W1'): 0.8734, ('MALE', 'H1', 'W2'): 1.7947,
    ('MALE', 'H1', 'W3'): 2.2386, ('MALE', 'H1', 'W4'): 2.5022,
    ('MALE', 'H2', 'W1'): 0.8307, ('MALE', 'H2', 'W2'): 1.7462,
    ('MALE', 'H2', 'W3'): 2.235, ('MALE', 'H2', 'W4'): 2.5076,
    ('MALE', 'H3', 'W1'): 0.7819, ('MALE', 'H3', 'W2'): 1.6871,
    ('MALE', 'H3', 'W3'): 2.2281, ('MALE', 'H3', 'W4'): 2.5096,
    ('MALE', 'H4', 'W1'): 0.7275, ('MALE', 'H4', 'W2'): 1.6178,
    ('MALE', 'H4', 'W3'): 2.2182, ('MALE', 'H4', 'W4'): 2.5084,
    ('FEMALE', 'H1', 'W1'): 1.5195, ('FEMALE', 'H1', 'W2'): 2.1536,
    ('FEMALE', 'H1', 'W3'): 2.5395, ('FEMALE', 'H1', 'W4'): 2.8949,
    ('FEMALE', 'H2', 'W1'): 1.4752, ('FEMALE', 'H2', 'W2'): 2.1355,
    ('FEMALE', 'H2', 'W3'): 2.5341, ('FEMALE', 'H2', 'W4'): 2.9007,
    ('FEMALE', 'H3', 'W1'): 1.4241, ('FEMALE', 'H3', 'W2'): 2.1135,
    ('FEMALE', 'H3', 'W3'): 2.5243, ('FEMALE', 'H3', 'W4'): 2.9018,
    ('FEMALE', 'H4', 'W1'): 1.3631, ('FEMALE', 'H4', 'W2'): 2.0877,
    ('FEMALE', 'H4', 'W3'): 2.5105, ('FEMALE', 'H4', 'W4'): 2.8986,
}


@dataclass(frozen=True)
class Phenotype:
    """anny's phenotype inputs, all in [0, 1]."""
    gender: float
    age: float
    height: float
    weight: float
    muscle: float
    proportions: float = PROPORTIONS

    def kwargs(self) -> dict:
        return {"gender": self.gender, "age": self.age, "height": self.height, "weight": self.weight,
                "muscle": self.muscle, "proportions": self.proportions}


def build_inputs(s: float) -> tuple[float, float]:
    """(weight, muscle) at position s in [0, 3] along the build path."""
    s = min(max(s, 0.0), len(_BUILD_PATH) - 1.0)
    k = min(int(s), len(_BUILD_PATH) - 2)
    (w0, m0), (w1, m1) = _BUILD_PATH[k], _BUILD_PATH[k + 1]
    f = s - k
    return w0 + (w1 - w0) * f, m0 + (m1 - m0) * f


def driver_phenotype(gender: str, height: str, weight: str) -> Phenotype:
    w, m = build_inputs(BUILD_INPUT[(gender, height, weight)])
    return Phenotype(GENDER[gender], ADULT_AGE, HEIGHT_INPUT[(gender, height)], w, m)


def child_phenotype(orientation: str = "FRONT_FACING") -> Phenotype:
    """A toddler of average build, gender-neutral (anny's gender 0.5): one year old in a rear-facing
    carrier, two and a half in a front-facing seat."""
    return Phenotype(0.5, CHILD_AGE[orientation], 0.5, 0.5, 0.5)


# ---------------------------------------------------------------------- calibration (needs anny)
def measure(model, phenotype: Phenotype) -> dict:
    """Stature (m), mass (kg) and BMI of a phenotype's rest body, by anny.Anthropometry."""
    import anny
    import torch
    with torch.no_grad():
        rest = model(pose_parameters=None, phenotype_kwargs=phenotype.kwargs())["rest_vertices"]
        a = anny.Anthropometry(model)(rest)
    return {"height_m": float(a["height"]), "mass_kg": float(a["mass"]), "bmi": float(a["bmi"])}


def _bisect(f, target: float, lo: float, hi: float, steps: int = 22) -> float:
    """x in [lo, hi] with f(x) = target for an increasing f."""
    for _ in range(steps):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if f(mid) < target else (lo, mid)
    return round((lo + hi) / 2, 4)


def calibrate(model) -> tuple[dict, dict]:
    heights, builds = {}, {}
    for gender, g in GENDER.items():
        for h, band in HEIGHT_BANDS.items():
            target = sum(band) / 2
            heights[(gender, h)] = _bisect(
                lambda x, g=g: measure(model, Phenotype(g, ADULT_AGE, x, 0.5, 0.5))["height_m"], target, 0.0, 1.0)
            for w, bmi in BMI_TARGET.items():
                def bmi_at(s, g=g, gender=gender, h=h):
                    weight, muscle = build_inputs(s)
                    return measure(model, Phenotype(g, ADULT_AGE, heights[(gender, h)], weight, muscle))["bmi"]
                builds[(gender, h, w)] = _bisect(bmi_at, bmi, 0.0, 3.0)
    return heights, builds


def measured_table(model) -> dict:
    """(gender, H, W) -> measured stature, mass, BMI of every driver body."""
    return {(g, h, w): measure(model, driver_phenotype(g, h, w))
            for g in GENDER for h in HEIGHT_BANDS for w in BMI_BANDS}


def describe_texts(table: dict) -> dict:
    """The technician texts of the space file, from the measured bodies."""
    out = {"driver_height": {}, "driver_weight": {}}
    for h, (lo, hi) in HEIGHT_BANDS.items():
        rendered = [v["height_m"] for (g, hh, w), v in table.items() if hh == h]
        out["driver_height"][h] = f"{lo:.2f}-{hi:.2f} m tall (rendered {min(rendered):.2f} m)"
    for w, (lo, hi) in BMI_BANDS.items():
        masses = [v["mass_kg"] for (g, h, ww), v in table.items() if ww == w]
        band = (f"BMI under {hi:.0f}" if w == "W1" else f"BMI {lo:.0f} and over" if w == "W4"
                else f"BMI {lo:.0f}-{hi:.0f}")
        out["driver_weight"][w] = (f"{WEIGHT_WORDS[w]}, {band} ({min(masses):.0f}-{max(masses):.0f} kg at 1.55-1.85 m)")
    return out


def main() -> None:
    from .model import load_model
    model = load_model()
    heights, builds = calibrate(model)
    HEIGHT_INPUT.update(heights)
    BUILD_INPUT.update(builds)
    print("HEIGHT_INPUT =", heights)
    print("BUILD_INPUT =", builds)
    table = measured_table(model)
    for key, v in table.items():
        print(key, {k: round(x, 3) for k, x in v.items()})
    for feature, texts in describe_texts(table).items():
        print(f"[features.{feature}] describe =", texts)


if __name__ == "__main__":
    main()
