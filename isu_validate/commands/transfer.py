"""``isu-validate transfer REAL... --labels MAP.toml --out DIR``: what a SUT trained on renders does on
labelled real photographs, beside the same SUT on renders, and how far the real photos are from the renders.

    isu-validate transfer real/statefarm --labels statefarm.toml --out transfer/shipped
    isu-validate transfer real/a real/b --labels a.toml --labels b.toml --model runs/mine/model \\
        --renders datasets/standard --out transfer/mine
    isu-validate transfer real/a --labels a.toml --sut openai:gpt-4o@https://api.openai.com/v1 --out transfer/gpt

A real set is a folder of class folders, a YOLO set (data.yaml, images/, labels/), a COCO .json or a CSV
of image and label; the label map (TOML) says what each label means as answers to the space's questions
(docs/ARCHITECTURE.md, "Labelled real photographs"). Per feature and set: accuracy, balanced accuracy
(Wilson and bootstrap 95% intervals), the majority-class baseline, the confusion matrix, the AUC where the
SUT gives probabilities (the reference ISU does), and a gallery of the wrong answers in report.html. The
renders beside them: --renders DATASET (asked the same questions; also KID/FID against each real set), else
a reference model's own held-out renders (from its stored features). Replies are cached in DIR/cache/sut:
the same command again goes on where it stopped. Real photographs are read to measure, never to train.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..transfer.arguments import add_real_set_arguments, parse_groups
from . import add_overwrite_option


def register(sub) -> None:
    p = sub.add_parser("transfer", help="what renders taught: a SUT on labelled real photos beside renders",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_real_set_arguments(p)
    p.add_argument("--sut", default="reference",
                   help="SUT spec: reference (default), openai:MODEL@URL, command:PROGRAM ARGS..., http:URL")
    p.add_argument("--sut-option", action="append", default=[], metavar="NAME=VALUE",
                   help="adapter option, repeatable (e.g. model_dir=runs/reference-training/model)")
    p.add_argument("--model", type=Path, help="a reference ISU model folder (`reference train --out`): "
                                              "the same as --sut-option model_dir=DIR")
    p.add_argument("--renders", type=Path, help="renders beside the real photos: a dataset (`isu-validate dataset "
                                                "--out`: asked too, and KID/FID) or a folder of renders (KID/FID; "
                                                "with their .label.json also --zero-shot)")
    p.add_argument("--repeats", type=int, default=1, help="SUT queries per photo, per-feature majority (default 1)")
    p.add_argument("--prompt-style", choices=("paper", "compact"), help="VQA prompt wording (default paper)")
    p.add_argument("--sut-timeout", type=float, default=60.0, help="seconds per SUT request (default 60)")
    p.add_argument("--threads", type=int, default=1,
                   help="torch CPU threads of the reference ISU (default 1: it reads one photo at a time, and on a "
                        "busy 2-core machine two threads spun against each other: 5-13 s a photo against 0.5-1 s)")
    p.add_argument("--out", type=Path, required=True,
                   help="folder for the report (new, or this same measurement's: it goes on where it stopped)")
    add_overwrite_option(p, "another command's output, or a transfer measurement of other sets or settings")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..transfer import TransferSettings, measure_transfer
    from .sut import parse_options

    options = parse_options(args.sut_option)
    if args.model:
        if args.sut != "reference":
            from ..errors import InputError
            raise InputError("--model is the reference ISU's model folder: leave out --sut, or use --sut-option")
        options["model_dir"] = str(args.model)
    settings = TransferSettings(tuple(args.real), tuple(args.labels), args.sut, options, args.space,
                                str(args.renders) if args.renders else None, args.layout, args.skip_conflicts,
                                parse_groups(args.groups), args.limit, args.repeats, args.prompt_style, args.seed,
                                args.device, args.sut_timeout, args.zero_shot)
    args.interrupted = (f"interrupted; the replies so far are cached in {args.out / 'cache' / 'sut'}: run the same "
                        "command again to continue")
    if args.sut == "reference":   # the embedded SUT runs torch here; any other SUT runs elsewhere
        import torch
        torch.set_num_threads(max(1, args.threads))
    summary = measure_transfer(settings, args.out, overwrite=args.overwrite)
    print(format_summary(summary))
    print(f"report: {args.out / 'report.html'}", file=sys.stderr)
    return 0


def format_summary(summary: dict) -> str:
    """One table per feature: each real set, then the renders; KID of each set against the renders."""
    from ..transfer.scores import format_said_by_label

    lines = []
    header = (f"{'':<30}{'n':>5} {'acc':>6} {'95% CI':>11} {'BA':>6} {'BA 95% CI':>11} {'majority':>13} "
              f"{'AUC':>6} {'P(+) med':>9}")
    for feature in summary["features"]:
        lines += ["", f"{feature}", header]
        rows = [(f"real {name}", s["scores"].get(feature)) for name, s in summary["sets"].items()]
        if summary.get("renders"):
            rows.append((f"renders ({summary['renders'].get('renderer') or '?'})",
                         summary["renders"]["scores"].get(feature)))
        lines += [_line(where, sc) for where, sc in rows if sc]
        for name, s in summary["sets"].items():
            lines += format_said_by_label(name, s["scores"].get(feature) or {})
    for name, r in (summary.get("realism") or {}).items():
        lines.append(f"KID {name} vs renders: {r['kid_mean']:.4f} ± {r['kid_std']:.4f} (FID {r['fid']:.1f}; "
                     f"n {r['n_real']} real, {r['n_renders']} renders)")
    if summary.get("zero_shot"):
        from ..transfer.zero_shot import format_zero_shot
        lines += format_zero_shot(summary["zero_shot"])
    return "\n".join(lines).lstrip("\n")


def _line(where: str, sc: dict) -> str:
    def num(v):
        return "-" if v is None else f"{v:.2f}"

    def ci(c):
        return "-" if not c else f"{c[0]:.2f}-{c[1]:.2f}"
    base = sc["majority_baseline"]
    answered = f"{sc['n']}" + (f"({sc['unanswered']}?)" if sc["unanswered"] else "")
    return (f"{where[:29]:<30}{answered:>5} {num(sc['accuracy']):>6} {ci(sc['accuracy_ci95']):>11} "
            f"{num(sc['balanced_accuracy']):>6} {ci(sc['balanced_accuracy_ci95']):>11} "
            f"{base['class'][:6] + ' ' + num(base['accuracy']):>13} {num(sc['auc']):>6} "
            f"{num(sc['p_positive_median']):>9}")
