"""The effectiveness summary as the text table ``bench effectiveness`` prints."""
from __future__ import annotations

import math

import numpy as np

from isu_validate.bench.effectiveness.summary import GOAL_A12, GOAL_RATIO, SutSummary


def _num(value: float, fmt: str) -> str:
    return "-" if value is None or not math.isfinite(value) else format(value, fmt)


def _mean_std(values: list[float]) -> str:
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return "-"
    mean = sum(finite) / len(finite)
    if len(finite) < 2:
        return f"{mean:5.1f}"
    std = math.sqrt(sum((v - mean) ** 2 for v in finite) / (len(finite) - 1))
    return f"{mean:5.1f} ± {std:4.1f}"


def format_summary(s: SutSummary) -> str:
    runs = ", ".join(f"{a} {s.runs[a]} runs x {s.tests[a]:.0f} tests" for a in s.algorithms)
    lines = [f"SUT {s.sut}: {s.description}", f"  {runs}", ""]
    others = [a for a in s.algorithms if a != s.baseline]
    header = f"  {'threshold':>9}" + "".join(f"  {a + ' fail%':>15}" for a in s.algorithms)
    header += "".join(f"  {a + '/' + s.baseline:>13} {'p':>8} {'A12':>5}" for a in others if s.comparisons)
    lines.append(header)
    by_key = {(r["threshold"], r["algorithm"]): r for r in s.comparisons}
    for j, t in enumerate(s.thresholds):
        row = f"  {t:>9g}" + "".join(f"  {_mean_std([r[j] for r in s.rates[a]]):>15}" for a in s.algorithms)
        for algo in others:
            c = by_key.get((t, algo))
            if c:
                ratio = _num(c["ratio"], ".2f") + ("x" if math.isfinite(c["ratio"]) else "")
                row += f"  {ratio:>13} {_num(c['p'], '.2g'):>8} {_num(c['A12'], '.2f'):>5}"
        lines.append(row)
    lines.append("")
    if s.diversity:
        lines.append(f"  RQ2: failures at the oracle threshold, scene encoding, k-means k = {s.clusters} over all runs "
                     "(per-run mean ± std)")
        for algo in s.algorithms:
            d = s.diversity.get(algo)
            if d:
                lines.append(f"    {algo:>10}  coverage {_num(d['coverage mean'], '.2f')} "
                             f"± {_num(d['coverage std'], '.2f')}"
                             f"   entropy {_num(d['entropy mean'], '.3f')} ± {_num(d['entropy std'], '.3f')}")
        for t in s.diversity_tests:
            lines.append(f"    {t['algorithm']} vs {s.baseline} {t['measure']}: p {_num(t['p'], '.2g')}, "
                         f"A12 {_num(t['A12'], '.2f')}")
        for algo, gaps in s.entropy_gaps.items():
            lines.append(f"    {algo} - {s.baseline} entropy over {len(gaps)} clusterings (k-means seeds): mean "
                         f"{_num(float(np.mean(gaps)), '+.3f')}, "
                         f"from {_num(min(gaps), '+.3f')} to {_num(max(gaps), '+.3f')}")
    if any(math.isfinite(v) for v in s.search_ms.values()):
        lines.append("  search CPU time per test (ask + diversity + tell, this thread): " +
                     ", ".join(f"{a} {_num(v, '.2f')} ms" for a, v in s.search_ms.items()))
    lines += _goal_lines(s)
    return "\n".join(lines)


def _goal_lines(s: SutSummary) -> list[str]:
    goal = s.goal
    if not goal:
        return []
    if "note" in goal:
        return [f"  goal: not assessed ({goal['note']})"]
    lines = [f"  goal at threshold {goal['threshold']:g} (the first where {s.baseline} finds < 10%: "
             f"{goal['baseline_rate']:.1f}%): ratio >= {GOAL_RATIO:g}, A12 >= {GOAL_A12}, entropy >= {s.baseline}'s"]
    for algo, g in goal["algorithms"].items():
        gaps = s.entropy_gaps.get(algo, [])
        unsure = " (the entropy gap's sign differs between clusterings: not a finding)" \
            if gaps and min(gaps) < 0 < max(gaps) else ""
        lines.append(f"    {algo:>10}  ratio {_num(g['ratio'], '.2f')}, A12 {_num(g['A12'], '.2f')}, "
                     f"entropy {_num(g['entropy'], '.3f')} vs {_num(g['baseline_entropy'], '.3f')}: "
                     f"{'met' if g['met'] else 'NOT met'}{unsure}")
    return lines
