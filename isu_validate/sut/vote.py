"""Combining K repeated answers to one scene: per-feature majority vote and consistency.

Tie handling (documented contract): among the options with the most votes, the one
given *first* (lowest repeat index) wins, and the tie is recorded in ``ties``.  This
keeps the vote deterministic and independent of option order; an inconsistent SUT
shows up in the consistency figures rather than as an invented failure.

Consistency of a feature = votes for the winning option / K (a repeat that errored,
left the key out or answered invalidly counts as disagreeing).  The scene's
consistency is the mean over its questions; ``unanimous`` is the share of questions
on which all K repeats gave the same valid answer (the paper saw over 90%).
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from .parse import ANSWERED, INVALID, MISSING


@dataclass
class Vote:
    answers: dict[str, str] = field(default_factory=dict)
    status: dict[str, str] = field(default_factory=dict)
    consistency: float = 1.0
    unanimous: float = 1.0
    by_feature: dict[str, float] = field(default_factory=dict)
    ties: dict[str, list[str]] = field(default_factory=dict)


def majority(keys: Sequence[str], runs: Sequence[tuple[Mapping[str, str], Mapping[str, str]]]) -> Vote:
    """``runs`` holds one (answers, status) pair per repeat, errored repeats included as ({}, {})."""
    vote, k = Vote(), max(len(runs), 1)
    for key in keys:
        given = [answers[key] for answers, _ in runs if key in answers]
        if not given:
            statuses = {status.get(key) for _, status in runs}
            vote.status[key] = INVALID if INVALID in statuses else MISSING
            vote.by_feature[key] = 0.0
            continue
        counts = Counter(given)
        top = max(counts.values())
        leaders = [option for option in dict.fromkeys(given) if counts[option] == top]
        if len(leaders) > 1:
            vote.ties[key] = leaders
        vote.answers[key], vote.status[key] = leaders[0], ANSWERED
        vote.by_feature[key] = top / k
    if keys:
        vote.consistency = sum(vote.by_feature.values()) / len(keys)
        vote.unanimous = sum(v == 1.0 for v in vote.by_feature.values()) / len(keys)
    return vote
