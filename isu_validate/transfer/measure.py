"""``transfer``: what a SUT trained (or tuned) on renders does on labelled real photographs, beside renders.

For each real photo set: its photos read in their layout, their labels mapped to answers (``realphotos``),
the SUT asked the questions the labels answer, and per feature the figures of ``scores``. Beside them the
same SUT on renders (``renders``), and KID/FID of each real set against the render images (``realism``'s
code). Writes to OUT: ``summary.json`` (the contract, docs/ARCHITECTURE.md "Transfer folder"),
``answers.jsonl`` (every question asked, with truth, answer and probabilities), ``report.html``, and the
SUT's replies in ``cache/sut`` (the same command again goes on where it stopped).
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..archive.output_dir import claim_output
from ..atomic import write_json, write_text
from ..errors import InputError
from ..realphotos import LabelledSet, label_photos, load_label_map, read_photo_set
from ..realphotos.groups import group_of, read_groups
from ..space import SceneSpace, load_space
from .ask import Item, ask_all
from ..sut.version import sut_version
from .scores import Answer, positive_class, said_by_label, score

FORMAT = "isu-validate-transfer/1"
SUMMARY, ANSWERS, REPORT = "summary.json", "answers.jsonl", "report.html"


@dataclass(frozen=True)
class TransferSettings:
    """What decides a transfer measurement (``device`` and ``sut_timeout_s`` do not: where and how patiently
    it runs)."""
    real: tuple[str, ...]                     # real photo sets (folders, a COCO .json, a .csv, a data.yaml)
    labels: tuple[str, ...]                   # label maps: one for every set, or one per set in order
    sut: str = "reference"
    sut_options: dict = field(default_factory=dict)
    space: str = "isu-paper"
    renders: str | None = None                # a dataset (scored and KID) or a folder of renders (KID only)
    layout: str | None = None                 # of every real set; None: told from the files
    skip_conflicts: bool = False
    groups: dict = field(default_factory=dict)   # set (its folder name or path as given) -> groups CSV
    limit: int | None = None                  # N labelled photos of each set, spread evenly through it
    repeats: int = 1
    prompt_style: str | None = None
    seed: int = 0                             # the bootstrap's and KID's subsets
    device: str = "auto"
    sut_timeout_s: float = 60.0
    zero_shot: bool = False                   # also the object score with no training (``zero_shot.py``)

    def identity(self, label_digests: list[str], sut_fingerprint: str) -> dict:
        out = {k: v for k, v in asdict(self).items() if k not in ("device", "sut_timeout_s", "labels")}
        if not self.zero_shot:   # off: the identity of a measurement made before the option existed
            del out["zero_shot"]
        out["real"] = [str(Path(r).resolve()) for r in self.real]
        out["renders"] = str(Path(self.renders).resolve()) if self.renders else None
        out["groups"] = {k: str(Path(v).resolve()) for k, v in self.groups.items()}
        out["label_maps"] = label_digests
        out["sut_fingerprint"] = sut_fingerprint
        return out


@dataclass
class RealSet:
    name: str
    labelled: LabelledSet
    items: list[Item]


def measure_transfer(settings: TransferSettings, out: Path, overwrite: bool = False, stream=None) -> dict:
    """Measure and write OUT (new, empty, or this same measurement's: it goes on); returns the summary."""
    from ..sut import open_sut

    started = time.perf_counter()
    space = load_space(settings.space)
    sets = read_real_sets(settings, space)
    features = list(dict.fromkeys(f for s in sets for item in s.items for f in item.truth))
    with open_sut(settings.sut, space=space, repeats=settings.repeats, cache_dir=out / "cache" / "sut",
                  timeout_s=settings.sut_timeout_s, device=settings.device, **settings.sut_options) as sut:
        # the SUT's fingerprint (its model, not the spelling of its path) decides the folder, as in replay
        identity = settings.identity([_digest(s) for s in sets], sut.adapter.fingerprint)
        claim_output(out, "transfer", identity, overwrite=overwrite).mark()
        write_json(out / SUMMARY, {"format": FORMAT, "complete": False}, indent=1)
        answered = {s.name: ask_all(sut, space, s.items, features, s.name, style=settings.prompt_style,
                                    stream=stream) for s in sets}
        rendered = _render_items(settings, space, features)
        beside, about = _renders(settings, space, features, sut, stream, rendered)
    summary = {"format": FORMAT, "complete": True, "settings": identity,
               "sut": {"spec": settings.sut, "options": settings.sut_options,
                       "version": sut_version(settings.sut, sut.adapter)["label"],
                       "device": getattr(sut.adapter, "device", None)},
               "features": features,
               "sets": {s.name: {**s.labelled.describe(),
                                 "scores": _scores(answered[s.name], space, features, settings.seed)} for s in sets},
               "renders": ({**about, "scores": _scores(beside, space, features, settings.seed)} if about else None)}
    summary["realism"] = _realism(settings, sets, stream)
    if settings.zero_shot:
        summary["zero_shot"] = _zero_shot(settings, space, sets, features, rendered)
    summary["seconds"] = round(time.perf_counter() - started, 1)
    _write(out, summary, answered, beside, space)
    return summary


def read_real_sets(settings: TransferSettings, space: SceneSpace) -> list[RealSet]:
    if not settings.real:
        raise InputError("give at least one real photo set")
    if len(settings.labels) not in (1, len(settings.real)):
        raise InputError(f"{len(settings.labels)} label maps for {len(settings.real)} real sets: give one --labels "
                         "for all sets, or one per set in the same order")
    if settings.limit is not None and settings.limit < 1:
        raise InputError(f"--limit must be 1 or more, got {settings.limit}")
    unknown = set(settings.groups) - {Path(r).name for r in settings.real} - set(settings.real)
    if unknown:
        raise InputError(f"--groups names {', '.join(sorted(unknown))}, which is no real set given "
                         f"({', '.join(Path(r).name for r in settings.real)})")
    sets, names = [], set()
    for i, root in enumerate(settings.real):
        label_map = load_label_map(settings.labels[min(i, len(settings.labels) - 1)], space)
        photo_set = read_photo_set(root, settings.layout)
        labelled = label_photos(photo_set, label_map, settings.skip_conflicts)
        labelled.source.update(label_map=str(label_map.path.resolve()), label_map_digest=label_map.digest)
        photos = _spread(labelled.photos, settings.limit)
        name = _unique(Path(root).name or f"set{i}", names)
        base = photo_set.root
        groups = _groups_of(settings, root)
        items = [Item(str(p.path.relative_to(base)) if p.path.is_relative_to(base) else str(p.path), p.path,
                      p.answers, group_of(groups, p.path, base) if groups else None, p.labels) for p in photos]
        missing = sum(item.group is None for item in items) if groups else 0
        if missing:
            raise InputError(f"the groups file of {root} names no group for {missing} of its labelled photos "
                             f"(e.g. {next(i.name for i in items if i.group is None)}): list every photo")
        sets.append(RealSet(name, labelled, items))
    return sets


def _spread(photos: list, limit: int | None) -> list:
    """``limit`` photos spread evenly through the set (every k-th: all its class folders, not the first)."""
    if not limit or limit >= len(photos):
        return photos
    return [photos[i * len(photos) // limit] for i in range(limit)]


def _groups_of(settings: TransferSettings, root: str) -> dict[str, str]:
    path = settings.groups.get(root) or settings.groups.get(Path(root).name)
    return read_groups(path) if path else {}


def _unique(name: str, taken: set) -> str:
    candidate, k = name, 2
    while candidate in taken:
        candidate, k = f"{name}-{k}", k + 1
    taken.add(candidate)
    return candidate


def _digest(s: RealSet) -> str:
    return s.labelled.source["label_map_digest"]


def _render_items(settings: TransferSettings, space: SceneSpace, features: list[str]):
    """(the render dataset or None, the renders whose truth is known): a dataset's, or a folder of frames with
    their labels; read once for the SUT and the zero-shot score."""
    from ..dataset.folder import DatasetDir
    from .renders import dataset_items, labelled_frames

    if not settings.renders:
        return None, []
    dataset = DatasetDir(Path(settings.renders))
    if dataset.is_dataset():
        return dataset, dataset_items(dataset, space, features)
    return None, labelled_frames(Path(settings.renders), space, features) if settings.zero_shot else []


def _renders(settings: TransferSettings, space: SceneSpace, features: list[str], sut, stream, rendered):
    """(records, what they were) of the SUT on renders: a dataset's, else a reference model's own held-out."""
    from .renders import held_out_records

    dataset, items = rendered
    if dataset is not None:
        records = ask_all(sut, space, items, features, "renders", style=settings.prompt_style, stream=stream)
        info = dataset.info()
        return records, {"source": f"dataset {settings.renders}", "renderer": info.get("renderer"),
                         "preset": (info.get("preset") or {}).get("name"), "scenes": len(items)}
    if settings.sut == "reference":
        from ..reference.model import default_model_dir

        return held_out_records(Path(settings.sut_options.get("model_dir") or default_model_dir()), space, features)
    return [], None


def _scores(records: list[dict], space: SceneSpace, features: list[str], seed: int) -> dict:
    out = {}
    for feature in features:
        options = space.features[feature].options
        positive = positive_class(options)
        asked = [r for r in records if feature in r["truth"]]
        answers = [Answer(r["truth"][feature], r["said"].get(feature),
                          (r["p"].get(feature) or {}).get(positive) if r.get("p") else None, r.get("group"))
                   for r in asked]
        if answers:
            out[feature] = score(answers, options, seed)
        if any(r.get("labels") for r in asked):
            rows = [(tuple(r.get("labels") or ()), a.truth, a.said, a.p_positive)
                    for r, a in zip(asked, answers, strict=True)]
            out[feature]["said_by_label"] = said_by_label(rows, positive)
    return out


def _realism(settings: TransferSettings, sets: list[RealSet], stream) -> dict | None:
    """KID/FID of each real set against the render images (None without a render set)."""
    if not settings.renders:
        return None
    from ..realism import FeatureExtractor, MetricSettings, compare_features
    from ..realism.cache import default_cache_dir
    from ..realism.features import stderr_progress
    from .renders import render_images

    extractor = FeatureExtractor(cache=default_cache_dir(), device=settings.device)
    renders = render_images(Path(settings.renders))
    f_renders = extractor.features(renders, stderr_progress("renders"))
    metric = MetricSettings(bootstrap=0, seed=settings.seed)
    out = {}
    for s in sets:
        f_real = extractor.features([item.image for item in s.items], stderr_progress(s.name))
        result = compare_features(f_real, f_renders, metric, extractor.report_settings())
        out[s.name] = {"fid": result.fid, "kid_mean": result.kid_mean, "kid_std": result.kid_std,
                       "n_real": result.n_a, "n_renders": result.n_b, "settings": result.settings,
                       "warnings": result.warnings}
    return out


def _zero_shot(settings: TransferSettings, space: SceneSpace, sets: list[RealSet], features: list[str],
               rendered) -> dict:
    """The zero-shot object score's AUC on each real set and on the renders whose truth is known."""
    import sys

    from .zero_shot import zero_shot_scores

    groups = {s.name: s.items for s in sets}
    if rendered[1]:
        groups["renders"] = rendered[1]
    return zero_shot_scores(groups, space, features, settings.device,
                            progress=lambda name, n: print(f"zero-shot: {name} ({n} frames)", file=sys.stderr))


def _write(out: Path, summary: dict, answered: dict, beside: list[dict], space: SceneSpace) -> None:
    import json

    from .report import write_report

    lines = [json.dumps({"set": name, **r}) for name, records in answered.items() for r in records]
    lines += [json.dumps({"set": "renders", **r}) for r in beside]
    write_text(out / ANSWERS, "\n".join(lines) + "\n")
    write_report(out / REPORT, summary, answered, space)
    write_json(out / SUMMARY, summary, indent=1)
