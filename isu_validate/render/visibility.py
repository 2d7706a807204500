"""Per-feature visibility from the segmentation: how much of what shows a feature the camera sees.

A predicted feature of the scene space names the render parts that show it (``visible_parts``,
instance names of ``labels.INSTANCES``: ``driver_face`` for gender and emotion, ``seat_belt``,
``luggage``...). Its visible share is

    pixels of those parts in the segmentation / pixels they would cover with nothing in front,

the denominator being the parts' unoccluded footprint (``footprint.py``). A feature whose share is
below its ``min_visible`` is *occluded*: the judge leaves it out of the response fitness and the
reports count it apart, so the search gets no credit for hiding things. Only things that exist have a
visibility: a feature whose true answer is NO or NONE shows nothing and is never occluded, and a
feature without ``visible_parts`` is always judged.

``min_visible`` comes from the space file per feature (default ``DEFAULT_MIN_VISIBLE``) and can be
overridden for a run: ``--min-visible 0.4`` (every feature) or ``--min-visible driver_gender=0.5``."""
from __future__ import annotations

from typing import Iterable, Mapping

from ..config import DEFAULT_MIN_VISIBLE   # a run setting's default, shown by `run --help`
from ..errors import InputError
from ..space import SceneSpace, SpaceError
from .labels import INSTANCE_ID

ABSENT_ANSWERS = ("NO", "NONE")  # true answers that mean "nothing there to see"
ALL = "*"                        # the override key that applies to every feature


def needed_parts(space: SceneSpace) -> list[str]:
    """Every part some predicted feature of the space is shown by, in first-mentioned order;
    a name that is not a render instance is refused with the known ones."""
    parts: dict[str, None] = {}
    for feature in space.predicted:
        for part in feature.visible_parts:
            if part not in INSTANCE_ID:
                raise SpaceError(f"{space.source}: feature {feature.name!r} names visible part {part!r}, which the "
                                 f"renderer does not draw; parts: {', '.join(sorted(INSTANCE_ID))}")
            parts[part] = None
    return list(parts)


def part_shares(visible: Mapping[str, Mapping], footprints: Mapping[str, int]) -> dict[str, dict]:
    """{part: {pixels, footprint, share}} from the visible instances and the footprint pixel counts.
    The share is capped at 1: the segmentation's sample jitter can put a pixel or two beyond the footprint."""
    out = {}
    for part, footprint in footprints.items():
        pixels = int(visible.get(part, {}).get("pixels", 0))
        out[part] = {"pixels": pixels, "footprint": int(footprint),
                     "share": round(min(1.0, pixels / footprint), 4) if footprint else 0.0}
    return out


def parse_min_visible(items: Iterable[str]) -> dict[str, float]:
    """``--min-visible`` values: ``SHARE`` (every feature) or ``FEATURE=SHARE``, each in [0, 1]."""
    out: dict[str, float] = {}
    for item in items:
        name, _, value = item.rpartition("=")
        try:
            share = float(value)
        except ValueError:
            raise InputError(f"--min-visible {item!r}: give a share in [0, 1] (e.g. 0.25) or FEATURE=SHARE") from None
        out[name.strip() or ALL] = share
    return out


def min_visible_for(space: SceneSpace, overrides: Mapping[str, float] | None = None) -> dict[str, float]:
    """The threshold of every feature that has visible parts: run override, else the space's
    ``min_visible``, else ``DEFAULT_MIN_VISIBLE``. Unknown features and shares outside [0, 1] are refused."""
    overrides = dict(overrides or {})
    judged = {f.name: f for f in space.predicted if f.visible_parts}
    for name, share in overrides.items():
        if name != ALL and name not in judged:
            raise InputError(f"--min-visible names {name!r}, which is not a predicted feature with visible_parts in "
                             f"space {space.name!r}; those are: {', '.join(judged) or 'none'}")
        if not 0.0 <= float(share) <= 1.0:
            raise InputError(f"--min-visible {name}={share}: a share must lie in [0, 1]")
    out = {}
    for name, feature in judged.items():
        default = DEFAULT_MIN_VISIBLE if feature.min_visible is None else feature.min_visible
        out[name] = float(overrides.get(name, overrides.get(ALL, default)))
    return out


def feature_visibility(space: SceneSpace, canonical: Mapping, parts: Mapping[str, Mapping],
                       min_visible: Mapping[str, float]) -> tuple[dict[str, float], list[str]]:
    """({feature: visible share}, [occluded features]) for the scene's active predicted features
    that show something. A thing whose parts fall wholly outside the frame has share 0."""
    shares, occluded = {}, []
    for q in space.questions(canonical):
        feature = space.features[q.key]
        if not feature.visible_parts or q.truth in ABSENT_ANSWERS:
            continue
        pixels = sum(parts.get(p, {}).get("pixels", 0) for p in feature.visible_parts)
        footprint = sum(parts.get(p, {}).get("footprint", 0) for p in feature.visible_parts)
        shares[q.key] = round(min(1.0, pixels / footprint), 4) if footprint else 0.0
        if shares[q.key] < min_visible.get(q.key, DEFAULT_MIN_VISIBLE):
            occluded.append(q.key)
    return shares, occluded


def without_hidden(scene: Mapping, label: Mapping) -> dict:
    """``scene`` less the features its frame hid (a render label's or a dataset entry's ``occluded``): what a
    frame can teach or be asked, as the judge leaves hidden features out of a verdict."""
    hidden = set(label.get("occluded") or ())
    return {name: value for name, value in scene.items() if name not in hidden}
