"""``isu-validate agree``: does the SUT behave the same on the real recreations as on the renders?

    isu-validate agree PAIRS --sut SPEC [--repeats 3] [--space S] --out DIR
    isu-validate agree votes PAIRS --annotator NAME [--vote SAMPLE=yes|no ...] [--redo]

Writes DIR/agreement.csv, DIR/summary.json, DIR/report.html (and answers.json). Exits 1 only when
nothing could be compared; every problem is named in the log and in the report. Stand-in frames
(`capture shoot --source standin`) are counted and flagged in every output. Interrupted, either
goes on where it stopped when run again the same way: agree from the SUT replies cached in
DIR/cache, votes from the votes already saved.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..devices import add_device_argument
from ..errors import InputError
from . import add_overwrite_option

INTERRUPTED = ("interrupted; the SUT replies so far are cached in {cache}: run the same command again to go on, "
               "nothing already answered is asked again")
VOTES_INTERRUPTED = ("interrupted; every vote given so far is saved: run the same command again to go on with "
                     "the pairs you have not voted on")


def register(sub) -> None:
    p = sub.add_parser("agree", help="per-feature sim/real agreement report (or: agree votes, validity votes)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", nargs="+", metavar="PAIRS", help="pairs directory; or the word 'votes' and PAIRS")
    p.add_argument("--sut", help="SUT spec: reference, openai:MODEL@URL, command:PROGRAM ARGS..., http:URL")
    p.add_argument("--sut-option", action="append", default=[], metavar="NAME=VALUE",
                   help="adapter option, as for run (e.g. model_dir=DIR for a retrained reference ISU)")
    p.add_argument("--repeats", type=int, default=3, help="SUT queries per image, per-feature majority (default 3)")
    p.add_argument("--space", help="scene space (default: the one named in the samples' scene.json)")
    p.add_argument("--out", type=Path, help="report folder")
    add_overwrite_option(p, "an agreement of other pairs or another SUT, or another command's output")
    p.add_argument("--include-invalid", action="store_true", help="keep pairs the annotators voted invalid")
    p.add_argument("--no-realism", action="store_true", help="skip FID/KID (the Inception pass is the slow part)")
    p.add_argument("--feature-cache", help="Inception feature cache folder (default ~/.cache/isu-validate/...)")
    p.add_argument("--threads", type=int, default=min(4, os.cpu_count() or 1), help="torch/BLAS threads for FID/KID")
    p.add_argument("--sut-timeout", type=float, default=60.0, help="seconds per SUT request")
    add_device_argument(p)
    p.add_argument("--json", action="store_true", help="print summary.json")
    v = p.add_argument_group("votes")
    v.add_argument("--annotator", help="votes: your name")
    v.add_argument("--vote", action="append", default=[], metavar="SAMPLE=yes|no",
                   help="votes: record without asking (repeatable)")
    v.add_argument("--redo", action="store_true", help="votes: ask again about pairs you voted on")
    p.set_defaults(func=run, interrupted=INTERRUPTED.format(cache="the --out folder's cache/sut"))


def run(args) -> int:
    if args.target[0] == "votes":
        args.interrupted = VOTES_INTERRUPTED
        return _votes(args)
    if len(args.target) != 1 or not args.sut or not args.out:
        raise InputError("usage: isu-validate agree PAIRS --sut SPEC --out DIR (see --help)")
    args.interrupted = INTERRUPTED.format(cache=args.out / "cache" / "sut")
    from ..agree import AgreeSettings, measure_agreement
    from .sut import parse_options
    settings = AgreeSettings(sut=args.sut, repeats=args.repeats, space=args.space,
                             include_invalid=args.include_invalid, realism=not args.no_realism,
                             threads=args.threads, feature_cache=args.feature_cache, sut_timeout_s=args.sut_timeout,
                             sut_options=parse_options(args.sut_option), device=args.device)
    result = measure_agreement(args.target[0], args.out, settings, overwrite=args.overwrite)
    s = result.summary
    if args.json:
        print(json.dumps(s, indent=2))
    else:
        print(_lines(s, args.out))
    if result.exit_code:
        print("agree: nothing could be compared (see the problems above and in the report)", file=sys.stderr)
    return result.exit_code


def _pct(v) -> str:
    return "-" if v is None else f"{100 * v:.1f}%"


def _frames(s: dict) -> str:
    if not s["stand_in_frames"]:
        return f"{s['n_frames']} real frames"
    return f"{s['n_frames']} 'real' frames, {s['stand_in_frames']} of them stand-in renders"


def _lines(s: dict, out: Path) -> str:
    from capture.sidecar import banner
    lines = [banner(s["stand_in_frames"], s["real_frames"])] if s["stand_in_frames"] else []
    lines += [f"agreement (sim vs real): {_pct(s['agreement_rate'])} of {s['n_features_compared']} features compared "
              f"on {s['n_samples']} samples ({_frames(s)})",
              f"  both correct {s['both_correct']}, both wrong {s['both_wrong']}, correct only on sim {s['sim_only']}, "
              f"correct only on real {s['real_only']}; not compared: "
              + ", ".join(f"{k} {v}" for k, v in s["not_compared"].items())]
    if s["stand_in_frames"] and s["real_frames"]:
        by = s["by_provenance"]
        lines.append("  apart: " + "; ".join(
            f"on {name} {_pct(by[kind]['agreement_rate'])} of {by[kind]['compared']} features "
            f"({by[kind]['frames']} frames)" for kind, name in (("real", "real captures"), ("stand_in", "stand-ins"))))
    if "agreement_rate_nst" in s:
        change = s["nst_change"]["change"]
        lines.append(f"agreement (nst vs real): {_pct(s['agreement_rate_nst'])} of {s['n_features_compared_nst']}; "
                     f"change {'-' if change is None else f'{100 * change:+.1f} points'} on "
                     f"{s['nst_change']['rows']} rows compared both ways")
    for key, name in (("", "sim"), ("_nst", "nst")):
        if s.get(f"fid{key}") is not None:
            lines.append(f"FID {name}/real {s[f'fid{key}']:.2f}, "
                         f"KID {s[f'kid_mean{key}']:.4f} ± {s[f'kid_std{key}']:.4f}")
    if s["validity"]["rate"] is not None:
        lines.append(f"reconstruction validity: {_pct(s['validity']['rate'])} ({s['validity']['valid']} valid, "
                     f"{s['validity']['invalid']} invalid, {s['validity']['tied']} tied)")
    if s["problems"]:
        lines.append(f"{len(s['problems'])} problem(s), listed in the report")
    lines.append(f"report: {out / 'report.html'}  csv: {out / 'agreement.csv'}  summary: {out / 'summary.json'}")
    return "\n".join(lines)


def _votes(args) -> int:
    from ..agree.review import write_review
    from ..agree.votes import tally
    from ..pairs import PairsDir
    if len(args.target) != 2 or not args.annotator:
        raise InputError("usage: isu-validate agree votes PAIRS --annotator NAME [--vote SAMPLE=yes|no ...]")
    pairs = PairsDir(args.target[1])
    pairs.require()
    if args.vote:
        _record_votes(pairs, args.annotator, args.vote)
    review = write_review(pairs)   # on every path: the annotator's page, with the votes so far
    print(f"review the pairs side by side in {review}")
    if not args.vote:
        try:
            _ask_votes(pairs, args.annotator, args.redo)
        finally:
            write_review(pairs)   # with the votes just given
    validity = tally(pairs.samples()).to_json()
    apart = f"; {len(validity['without_render'])} without sim.png, not counted" if validity["without_render"] else ""
    print(f"validity: {_pct(validity['rate'])} ({validity['valid']} valid, {validity['invalid']} invalid, "
          f"{validity['tied']} tied, {validity['unvoted']} without votes{apart})")
    return 0


def _record_votes(pairs, annotator: str, items: list[str]) -> None:
    """``--vote SAMPLE=yes|no``: every item is checked before the first is stored."""
    from ..agree.votes import parse_answer
    given = []
    for item in items:
        name, _, answer = item.partition("=")
        same = parse_answer(answer)
        if same is None:
            raise InputError(f"--vote {item!r}: write SAMPLE=yes or SAMPLE=no")
        sample = pairs.sample(name)
        if not sample.sim.is_file():
            raise InputError(f"--vote {item!r}: {sample.sim} is missing, so there is no pair to vote on")
        given.append((sample, same))
    for sample, same in given:
        sample.record_vote(annotator, same)


def _ask_votes(pairs, annotator: str, redo: bool) -> None:
    """One question per pair on the terminal; each answer is saved at once (stop any time, go on later)."""
    from ..agree.votes import parse_answer
    print("answer y (same scenario), n (not), s (skip), q (quit)")
    given = 0
    for sample in pairs.samples():
        if (annotator in sample.votes() and not redo) or not sample.sim.is_file():
            continue
        frames = ", ".join(str(f) for f in sample.real_frames()) or "no real frames"
        while True:
            try:
                answer = input(f"{sample.name}: {sample.sim} vs {frames}: same scenario? [y/n/s/q] ").strip().lower()
            except EOFError:   # no terminal: one line, not a traceback; every vote given is already saved
                print()
                raise InputError(f"no answer to read: standard input is closed or at its end (no terminal?); "
                                 f"the {given} vote(s) given are saved; vote in a terminal, or without one with "
                                 "--vote SAMPLE=yes|no") from None
            if answer in ("q", "quit"):
                return
            if answer in ("s", "skip"):
                break
            same = parse_answer(answer)
            if same is not None:
                sample.record_vote(annotator, same)
                given += 1
                break
