"""``agree``: does the SUT behave the same on the real recreation of a scene as on its render?

    result = measure_agreement("pairs/", "agree/", AgreeSettings(sut="reference", repeats=3))

Rooms: ``ask`` (the SUT on each image, judged), ``compare`` (categories, agreement, summary),
``votes`` (reconstruction validity), ``gap`` (FID/KID), ``report`` (HTML with the heatmap).
Outputs (a contract): ``agreement.csv``, ``summary.json``, ``report.html``; ``answers.json`` keeps
what the SUT said about every image. Stand-in frames (renders taken for photos, their sidecars say so)
are counted and flagged in all three.
"""
from __future__ import annotations

import csv
import json
import os
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..archive.output_dir import claim_output
from ..atomic import atomic_open, write_text
from ..pairs import PairsDir, PairsError, Sample
from ..space import SceneSpace, SpaceError, load_space
from .ask import Asked, Asker
from .compare import COMPARED, CSV_COLUMNS, PROVENANCE, rows_for_frame, summarise
from .votes import INVALID, tally
from ..errors import InputError

__all__ = ["AgreeResult", "AgreeSettings", "agree"]


@dataclass
class AgreeSettings:
    """The SUT ``agree`` asks and how (``isu-validate agree`` flags).

        AgreeSettings(sut="reference", repeats=3, realism=False)
    """
    sut: str
    repeats: int = 3
    space: str | None = None            # None: the space named in the samples' scene.json
    include_invalid: bool = False       # pairs the annotators voted "not the same scenario"
    realism: bool = True                # FID/KID (needs the Inception weights; slow on the CPU)
    threads: int = 2
    feature_cache: str | None = None    # Inception feature cache (default: the realism command's)
    sut_timeout_s: float = 60.0
    sut_options: dict = field(default_factory=dict)
    device: str = "auto"                # torch work: the reference ISU's backbone and Inception (devices.py)


@dataclass
class SampleAnswers:
    sample: Sample
    sim: Asked | None = None
    nst: Asked | None = None
    real: dict[str, Asked] = field(default_factory=dict)


@dataclass
class AgreeResult:
    summary: dict
    rows: list[dict]
    answers: list[SampleAnswers]
    problems: list[str]

    @property
    def exit_code(self) -> int:
        return 0 if self.summary["n_features_compared"] else 1


def measure_agreement(pairs_path: str | os.PathLike, out: str | os.PathLike, settings: AgreeSettings,
                      log=None, overwrite: bool = False) -> AgreeResult:
    """Ask the SUT about every render and real photo of a pairs directory and compare per feature
    (``isu-validate agree``): writes ``out/agreement.csv``, ``summary.json``, ``report.html``. ``out`` must be
    new or this same agreement's folder (it goes on where it stopped); anything else needs ``overwrite``.

        result = measure_agreement("pairs/", "agree/", AgreeSettings(sut="reference", repeats=3))
        result.summary["agreement_rate"]
    """
    log = log or (lambda text: print(f"agree: {text}", file=sys.stderr, flush=True))
    out = Path(out)
    samples = PairsDir(pairs_path).samples()
    validity = tally(samples)
    space = _space(samples, settings.space)
    from ..sut import open_sut
    sut = open_sut(settings.sut, space=space, repeats=settings.repeats, cache_dir=out / "cache" / "sut",
                   timeout_s=settings.sut_timeout_s, device=settings.device, **settings.sut_options)
    asker, problems, rows, answered = Asker(sut, space), [], [], []

    def problem(text: str) -> None:
        problems.append(text)
        log(text)

    try:
        identity = {"pairs": str(Path(pairs_path).resolve()), "sut_fingerprint": sut.adapter.fingerprint,
                    "repeats": settings.repeats, "include_invalid": settings.include_invalid}
        # only now: a bad option or input leaves no folder behind
        claim_output(out, "agree", identity, overwrite=overwrite).mark()
        for k, sample in enumerate(samples, 1):
            if validity.by_sample.get(sample.name) == INVALID and not settings.include_invalid:
                problem(f"{sample.name}: voted not the same scenario by its annotators: left out "
                        "(--include-invalid keeps it)")
                continue
            log(f"{k}/{len(samples)} {sample.name}")
            result = _sample(sample, space, asker, problem)
            if result is not None:
                answers, sample_rows = result
                answered.append(answers)
                rows += sample_rows
                _write_answers(out, answered)
    finally:
        sut.close()
    summary = summarise(rows)
    summary["validity"] = validity.to_json()
    summary["realism"] = _gap(answered, rows, settings, problem) if settings.realism else {"skipped": "--no-realism"}
    summary.update(_realism_headline(summary["realism"]))
    if settings.realism and summary["stand_in_frames"] and summary["real_frames"]:   # a mixed folder: apart too
        summary["realism_by_provenance"] = {kind: _gap(answered, rows, settings, problem, flag)
                                            for kind, flag in PROVENANCE.items()}
    summary["problems"] = problems
    summary["settings"] = {**{k: v for k, v in asdict(settings).items() if k != "sut_options"},
                           "space": space.name, "space_hash": space.hash, "pairs": str(Path(pairs_path).resolve()),
                           "frames_compared_separately": True, "both_wrong_counts_as_agreement": True,
                           "sut_device": getattr(sut.adapter, "device", None)}   # None: the SUT runs elsewhere
    _write(out, rows, summary)
    from .report import write_report
    write_report(out / "report.html", summary, rows, answered, space)
    return AgreeResult(summary, rows, answered, problems)


def _space(samples: list[Sample], name: str | None) -> SceneSpace:
    if name is None:
        names = set()
        for s in samples:
            try:
                names.add(s.label().get("space", "isu-paper"))
            except PairsError:
                continue
        if len(names) > 1:
            raise InputError(f"the samples come from several scene spaces ({', '.join(sorted(names))}); "
                             "pass --space NAME to compare the samples of one")
        name = names.pop() if names else "isu-paper"
    return load_space(name)


def _sample(sample: Sample, space: SceneSpace, asker: Asker, problem) -> tuple[SampleAnswers, list[dict]] | None:
    """Ask about every image of one sample; None (with the reason logged) when it cannot be compared."""
    try:
        label = sample.label()
        scene = sample.scene()
    except PairsError as exc:
        problem(f"{sample.name}: {exc}")
        return None
    if label.get("space", space.name) != space.name:
        problem(f"{sample.name}: scene.json is from the scene space {label.get('space')!r}, not {space.name!r}: "
                f"not compared (pass --space {label.get('space')} to compare the samples of that space)")
        return None
    try:
        canonical = space.check(scene)
    except SpaceError as exc:
        problem(f"{sample.name}: scene.json does not fit the space {space.name!r}: {exc}: not compared")
        return None
    if label.get("space_hash") not in (None, space.hash):
        problem(f"{sample.name}: the space {space.name!r} changed since the run (hash {label['space_hash']} -> "
                f"{space.hash}); the truth is recomputed from the current space")
    frames, marks = sample.real_frames(), sample.provenance()
    if not frames:
        problem(f"{sample.name}: no real frames (real/*.png): capture them with "
                f"`isu-validate capture shoot --source SPEC --pair {sample.path}`")
        return None
    truth = {q.key: q.truth for q in space.questions(canonical)}
    occluded = set(label.get("occluded", [])) & set(truth)
    answers = SampleAnswers(sample, sim=_ask(asker, canonical, sample.sim, sample.name, problem))
    if answers.sim.unreadable:
        return None   # no render to compare with
    if sample.nst.is_file():
        answers.nst = _ask(asker, canonical, sample.nst, sample.name, problem)
    rows = []
    for frame in frames:
        real = answers.real[frame.name] = _ask(asker, canonical, frame, sample.name, problem)
        if real.unreadable:
            continue   # a broken frame has no rows; a frame the SUT failed on has sut_error rows
        rows += rows_for_frame(sample.name, frame.name, truth, occluded, answers.sim.judged, real.judged,
                               answers.nst.judged if answers.nst else None, frame in marks.stand_in)
    return answers, rows


def _ask(asker: Asker, scene: dict, image: Path, sample: str, problem) -> Asked:
    asked = asker.ask(scene, image)
    for text in asked.problems:
        problem(f"{sample}: {text}")
    return asked


def _gap(answered: list[SampleAnswers], rows: list[dict], settings: AgreeSettings, problem,
         stand_in: bool | None = None) -> dict:
    """FID/KID over the compared samples; ``stand_in`` True/False: over the stand-in or real frames alone."""
    kind = {(r["sample"], r["frame"]): r["stand_in"] for r in rows if stand_in in (None, r["stand_in"])}
    compared = {r["sample"] for r in rows if r["category"] in COMPARED and (r["sample"], r["frame"]) in kind}
    use = [a for a in answered if a.sample.name in compared]
    sim = [a.sample.sim for a in use]
    real = [a.sample.real_dir / f for a in use for f, asked in a.real.items()
            if not asked.unreadable and (a.sample.name, f) in kind]
    nst = [a.sample.nst for a in use if a.nst and not a.nst.unreadable]
    from .gap import domain_gap
    try:
        cache = Path(settings.feature_cache) if settings.feature_cache else None
        return domain_gap(sim, real, nst, settings.threads, cache, device=settings.device)
    except (OSError, ValueError, RuntimeError) as exc:
        problem(f"FID/KID not computed: {exc}")
        return {"skipped": str(exc)}


def _realism_headline(realism: dict) -> dict:
    out = {"fid": None, "kid_mean": None, "kid_std": None}
    for key, suffix in (("sim_vs_real", ""), ("nst_vs_real", "_nst")):
        if key in realism:
            out.update({f"fid{suffix}": realism[key]["fid"], f"kid_mean{suffix}": realism[key]["kid_mean"],
                        f"kid_std{suffix}": realism[key]["kid_std"]})
    return out


def _write(out: Path, rows: list[dict], summary: dict) -> None:
    with atomic_open(out / "agreement.csv", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")


def _write_answers(out: Path, answered: list[SampleAnswers]) -> None:
    """What the SUT said about every image so far (rewritten after each sample)."""
    def one(asked: Asked | None):
        if asked is None:
            return None
        return {"answers": asked.answers, "error": asked.judged.error, "problems": asked.problems,
                "consistency": asked.consistency, "raw": asked.raw}
    data = {a.sample.name: {"sim": one(a.sim), "nst": one(a.nst), "real": {f: one(x) for f, x in a.real.items()}}
            for a in answered}
    write_text(out / "answers.json", json.dumps(data, indent=1) + "\n")
