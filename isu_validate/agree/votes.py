"""Reconstruction validity: did the recreation show the same scenario? Annotators vote yes or no per pair.

A pair is valid when most of its annotators said yes, invalid when most said no, and tied when
the votes split evenly (neither confirmed nor rejected: kept in the agreement, flagged). The
validity rate is valid / voted pairs, as the paper's majority of three annotators. A sample whose
render (``sim.png``) is gone is no pair: its votes are not counted, and it is named apart.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..pairs import Sample

VALID, INVALID, TIED, UNVOTED = "valid", "invalid", "tied", "unvoted"


def verdict(votes: dict[str, bool]) -> str:
    yes = sum(votes.values())
    no = len(votes) - yes
    if not votes:
        return UNVOTED
    return VALID if yes > no else INVALID if no > yes else TIED


@dataclass
class Validity:
    by_sample: dict[str, str] = field(default_factory=dict)
    votes: dict[str, dict[str, bool]] = field(default_factory=dict)
    without_render: list[str] = field(default_factory=list)   # no sim.png: nothing was compared, not counted

    def names(self, kind: str) -> list[str]:
        return [s for s, v in self.by_sample.items() if v == kind]

    @property
    def rate(self) -> float | None:
        voted = len(self.by_sample) - len(self.names(UNVOTED))
        return len(self.names(VALID)) / voted if voted else None

    def to_json(self) -> dict:
        return {"rate": self.rate, **{k: len(self.names(k)) for k in (VALID, INVALID, TIED, UNVOTED)},
                "invalid_samples": self.names(INVALID), "tied_samples": self.names(TIED),
                "annotators": sorted({a for v in self.votes.values() for a in v}),
                "without_render": self.without_render}


def tally(samples: list[Sample]) -> Validity:
    result = Validity()
    for sample in samples:
        if not sample.sim.is_file():
            result.without_render.append(sample.name)
            continue
        votes = sample.votes()
        result.votes[sample.name] = votes
        result.by_sample[sample.name] = verdict(votes)
    return result


def parse_answer(text: str) -> bool | None:
    """y/yes/same/1 -> True, n/no/different/0 -> False, anything else None."""
    word = text.strip().lower()
    if word in ("y", "yes", "same", "1", "true"):
        return True
    if word in ("n", "no", "different", "0", "false"):
        return False
    return None
