"""The search algorithms a user can name, and the one parser of their names on every command line
(``run --algorithm``, ``bench search --algorithm``, ``bench effectiveness --algorithms/--baseline``)."""
from __future__ import annotations

import argparse

ALGORITHMS = ("surrogate", "nsga2", "rs")


def parse_algorithms(text: str) -> list[str]:
    """Names from a comma-separated list ("surrogate,nsga2,rs"), in order, each once; a ValueError
    naming the unknown ones and the known ones otherwise."""
    names = list(dict.fromkeys(n.strip() for n in str(text).split(",") if n.strip()))
    unknown = [n for n in names if n not in ALGORITHMS]
    if unknown or not names:
        given = f"unknown algorithm{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))}" if unknown \
            else "no algorithm given"
        raise ValueError(f"{given}; the algorithms are {', '.join(ALGORITHMS)}")
    return names


def check_algorithm(name: str) -> str:
    """One algorithm name, checked like ``parse_algorithms`` checks a list."""
    names = parse_algorithms(name)
    if len(names) != 1:
        raise ValueError(f"one algorithm expected, got {', '.join(names)}; the algorithms are {', '.join(ALGORITHMS)}")
    return names[0]


def _option(parse):
    """An argparse ``type=`` from a parser: its ValueError becomes argparse's usage error, message kept."""
    def option(text: str):
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    option.__name__ = parse.__name__
    return option


algorithms_option = _option(parse_algorithms)   # a comma-separated list of algorithms
algorithm_option = _option(check_algorithm)     # one algorithm
