"""The bench's table: per row (model), the replayed run's failure rates and their cut against the shipped
model, McNemar's p, the held-out accuracy change, what the row's data cost; and whether the goal holds."""
from __future__ import annotations

THRESHOLDS = (0.8, 0.9, 1.0)
GOAL_AT = 0.9          # the goal's threshold
GOAL_CUT = 0.40        # the focused model cuts the failure rate at GOAL_AT by at least this share
GOAL_RATIO = 2.0       # ... and by at least this many times the uniform model's cut
GOAL_DROP = 0.02       # ... while no feature's held-out accuracy falls by more than this

LABELS = {"none": "none (shipped)", "uniform": "uniform N", "focused": "focused N",
          "focused-style": "focused N + style"}


def cut(rate: float | None, base: float | None) -> float | None:
    """The share of the base failure rate a model removes (negative: it fails more)."""
    if rate is None or not base:
        return None
    return 1.0 - rate / base


def table_rows(rates: dict[str, dict[float, float | None]], ps: dict[str, float], models: dict,
               costs: dict) -> list[dict]:
    """One row per model: ``rates`` {row: {threshold: rate}}, ``ps`` {row: McNemar's p against the shipped
    model}, ``models`` {row: retrain stage} (none for "none"), ``costs`` {row: {"renders", "styled", "minutes"}}."""
    base = rates["none"]
    out = []
    for name, by_t in rates.items():
        model = models.get(name)
        out.append({"row": name, "rates": by_t, "cuts": {t: cut(by_t[t], base[t]) for t in THRESHOLDS},
                    "p": ps[name] if name != "none" else None,
                    "worst": model["change"]["worst"] if model else None,
                    "worst_feature": model["change"]["worst_feature"] if model else None,
                    "mean": model["change"]["mean"] if model else None, **costs.get(name, {})})
    return out


def goal(rows: list[dict]) -> dict:
    by = {r["row"]: r for r in rows}
    focused, uniform = by.get("focused"), by.get("uniform")
    if focused is None or uniform is None:
        return {"verdict": "not measured (needs the uniform and focused rows)"}
    f_cut, u_cut = focused["cuts"][GOAL_AT], uniform["cuts"][GOAL_AT]
    checks = {f"focused cut at {GOAL_AT} >= {GOAL_CUT:.0%}": f_cut is not None and f_cut >= GOAL_CUT,
              f"focused cut >= {GOAL_RATIO:g}x the uniform cut": f_cut is not None and (
                  u_cut is None or u_cut <= 0 or f_cut >= GOAL_RATIO * u_cut),
              f"no held-out accuracy falls more than {GOAL_DROP * 100:.0f} points": focused["worst"] >= -GOAL_DROP}
    return {"checks": checks, "verdict": "met" if all(checks.values()) else "not met"}


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{x:.1%}"


def _signed(x: float | None) -> str:
    return "-" if x is None else f"{0.0 - x + 0.0:+.0%}"      # a cut of 40% is a change of -40% (no "-0%")


def format_table(rows: list[dict], n: int) -> str:
    head = ["model"] + [f"fail@{t} (vs none)" for t in THRESHOLDS] + [
        f"McNemar p @{GOAL_AT}", "worst held-out change", "mean change", "renders", "minutes"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        rates = [f"{_pct(r['rates'][t])}" + (f" ({_signed(r['cuts'][t])})" if r["row"] != "none" else "")
                 for t in THRESHOLDS]
        worst = "-" if r["worst"] is None else f"{r['worst'] * 100:+.1f} pt ({r['worst_feature']})"
        mean = "-" if r["mean"] is None else f"{r['mean'] * 100:+.2f} pt"
        renders = str(r.get("renders", "-")) + (f" + {r['styled']} styled" if r.get("styled") else "")
        minutes = "-" if r.get("minutes") is None else f"{r['minutes']:.1f}"
        p = "-" if r["p"] is None else f"{r['p']:.3g}"
        lines.append("| " + " | ".join([LABELS.get(r["row"], r["row"]).replace("N", str(n)), *rates, p, worst,
                                         mean, renders, minutes]) + " |")
    return "\n".join(lines)


def format_goal(result: dict) -> str:
    if "checks" not in result:
        return f"goal: {result['verdict']}"
    marks = "; ".join(f"{'yes' if ok else 'NO'}: {text}" for text, ok in result["checks"].items())
    return f"goal {result['verdict']}: {marks}"
