"""Training datasets from the renderer: images with their scene, truth, occlusion, COCO instance masks and
VQA conversations, drawn uniformly or focused where earlier runs failed (``isu-validate dataset``).

    summary = build_dataset(DatasetSettings(n=200, from_runs=("runs/s1",), focus="failing"), "datasets/near")
    scenes = focus_scenes(space, ["runs/s1"], "failing", 200, np.random.default_rng(0))

Rooms: ``settings`` (what a dataset is made of), ``plan`` (scene per slot), ``focus`` + ``rules`` (regions
near failures, rules read back), ``images`` (one slot in any process: render, masks, style copies),
``styles``, ``coco``, ``vqa``, ``folder`` (the layout: one reader and writer), ``outputs`` and ``card``
(the files of a complete dataset), ``build`` (the whole, resumable).
"""
from __future__ import annotations

from ..lazy import lazy_names

_NAMES = {"build_dataset": ".build", "DatasetSummary": ".build", "DatasetSettings": ".settings",
          "focus_scenes": ".focus", "focus_regions": ".focus", "load_focus_runs": ".focus",
          "FocusedScene": ".focus", "Region": ".focus", "parse_rule": ".rules", "Rule": ".rules",
          "DatasetDir": ".folder", "open_dataset": ".folder", "DatasetError": ".folder"}
__all__ = sorted(_NAMES)

__getattr__, __dir__ = lazy_names(__name__, _NAMES)
