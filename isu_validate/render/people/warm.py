"""Filling the people cache ahead of runs (``isu-validate people warm``), and measuring every cached
body against the cabin (``isu-validate people check``).

A run poses a body only on a cache miss (anny loaded once per process, ~0.9 GB, then ~1-4 s a body
and phone position on two cores); warming poses all 704 drivers (2 genders x 4 heights x 4 weights x
2 expressions x 11 phone positions), isu-diverse's empty hands and gazes on the bodies at the classes' corners,
both children and every outfit (2 kinds x 3 hair styles x 5 tops: the garments and accessories cut on the rest
body) once, so runs and pools seldom load anny. Dressing a
posed driver in an outfit needs no anny: runs do it on a miss (about a second a garment)."""
from __future__ import annotations

import itertools

import numpy as np

from ...progress import Progress
from .checks import child_measures, driver_measures
from .garments import TOPS
from .hair import STYLES
from .people import HAIR_STYLE, People
from .phenotype import BMI_BANDS, GENDER, HEIGHT_BANDS
from .store import load_entry

EMOTIONS = ("HAPPY", "SERIOUS")
PHONE_POSITIONS = ("NONE",) + tuple(f"P{i}" for i in range(1, 11))


def driver_grid(limit: int | None = None) -> list[tuple]:
    """Every driver (gender, height, weight, emotion, phone position); ``limit`` takes an even spread."""
    grid = list(itertools.product(GENDER, HEIGHT_BANDS, BMI_BANDS, EMOTIONS, PHONE_POSITIONS))
    if limit and limit < len(grid):
        grid = [grid[int(i)] for i in np.linspace(0, len(grid) - 1, limit)]
    return grid


# the bodies at the corners of the height and weight classes
CORNERS = (("FEMALE", "H1", "W1"), ("MALE", "H4", "W4"), ("FEMALE", "H4", "W1"), ("MALE", "H1", "W4"))


def hands_grid(cabin: dict, limit: int | None = None) -> list[tuple]:
    """Each of the rig's empty-hand positions (isu-diverse's driver_hands) without a phone, on the bodies at the
    classes' corners (with a ``limit``: on one), as ``People.driver_state`` arguments."""
    corners = CORNERS[:1] if limit else CORNERS
    return [(gender, height, weight, "SERIOUS", "NONE", None, hands)
            for hands in cabin.get("hand_positions", {}) for gender, height, weight in corners]


def gaze_grid(cabin: dict, limit: int | None = None) -> list[tuple]:
    """Each of the rig's gaze targets (isu-diverse's driver_gaze), the hands on the wheel and with the phone at the
    ear (which turns with the head), on the bodies at the classes' corners (with a ``limit``: on one)."""
    corners = CORNERS[:1] if limit else CORNERS
    return [(gender, height, weight, "SERIOUS", phone, None, "WHEEL", gaze)
            for gaze in cabin.get("gaze_targets", {}) for phone in ("NONE", "P1") for gender, height, weight in corners]


def pose_grid(cabin: dict, limit: int | None = None) -> list[tuple]:
    """Every driver the cache is warmed with and checked on."""
    return driver_grid(limit) + hands_grid(cabin, limit) + gaze_grid(cabin, limit)


def warm(people: People, limit: int | None = None) -> dict:
    """Pose every driver and both children into the cache; returns counts and the time of the misses."""
    grid = pose_grid(people.cabin, limit)
    outfits = outfit_grid(limit)
    progress = Progress(len(grid) + 2 + len(outfits), label="people", verdicts=False)
    before = people.misses
    for key in grid:
        people.driver_state(*key)
        progress.update()
    for front in (True, False):
        people.child_state(front)
        progress.update()
    for key in outfits:
        people.outfit(*key)
        progress.update()
    progress.close()
    return {"drivers": len(grid), "children": 2, "outfits": len(outfits), "posed": people.misses - before}


def outfit_grid(limit: int | None = None) -> list[tuple]:
    """Every outfit (kind, hair style, top); with a ``limit``, only each kind's T-shirt in its usual style."""
    if limit:
        return [(kind, HAIR_STYLE[kind], "TSHIRT") for kind in ("male", "female")]
    return list(itertools.product(("male", "female"), STYLES, TOPS))


def check(people: People, limit: int | None = None) -> dict:
    """Worst figures over every (cached or posed) body: clearances, belt, phone in hand."""
    worst: dict[str, tuple[float, tuple]] = {}
    grid = pose_grid(people.cabin, limit)
    progress = Progress(len(grid), label="checked", verdicts=False)
    topologies = {kind: load_entry(people.topology(kind)) for kind in ("male", "female")}
    for key in grid:
        topology = topologies["female" if key[0] == "FEMALE" else "male"]
        for name, value in driver_measures(load_entry(people.driver_state(*key)), topology, people.cabin).items():
            if name not in worst or is_worse(name, value, worst[name][0]):
                worst[name] = (value, key)
        progress.update()
    progress.close()
    for front in (True, False):
        state = load_entry(people.child_state(front))
        for name, value in child_measures(state, front, people.cabin["anchors"]["child_seat"]).items():
            worst[f"child_{'front' if front else 'rear'}_{name}"] = (value, ())
    return worst


def is_worse(name: str, value: float, than: float) -> bool:
    """Whether a driver figure is worse than another: a clearance, a belt's smallest distance to the body
    (negative: through it), its resting share, the hand's clearance to the phone and its touch on the
    phone's screen half the smaller it is; the phone's gap to the palm the larger."""
    if name.endswith(("_resting", "_min")) or name.startswith(("clear", "phone_clear", "phone_front")):
        return value < than
    return abs(value) > abs(than)
