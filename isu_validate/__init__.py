"""isu-validate: search-based testing of VLM in-car scene understanding, validated against the real world.

The public API is a handful of functions, each the one its command calls::

    import isu_validate as iv

    space = iv.load_space("isu-paper")                              # scene space
    config = iv.RunConfig(iv.PipelineConfig(run_dir="runs/s1", sut="reference", preset="draft"),
                          budget_tests=4, pop_size=2, seed=3)
    summary = iv.run_search(config)                                 # isu-validate run
    tests = iv.tests_table(summary.run_dir)                         # isu-validate export, as a DataFrame

- scene space: ``load_space``
- render: ``open_renderer`` (a warm Blender worker; use it as a context manager), ``load_camera``
- SUT: ``open_sut``, ``build_request``; judge: ``make_judge``
- search: ``run_search`` with ``RunConfig`` and ``PipelineConfig``; ``tests_table``; ``report``
- sim-to-real (RQ3): ``plan_recreation`` (pairs and sheets), ``measure_agreement`` with ``AgreeSettings``
- training data: ``build_dataset`` with ``DatasetSettings`` (images, truth, COCO masks, VQA chats)
- regression replay: ``replay_run`` with ``ReplaySettings`` (a new SUT on a run's stored images)

Names load on first use (PEP 562), so ``import isu_validate`` stays fast and imports neither
Blender, torch, scikit-learn, pandas, OpenCV nor pymoo. Each name's docstring has an example.
"""
from __future__ import annotations

from .lazy import lazy_names

__version__ = "0.1.0"

# public name -> the module it lives in (the name is the same there)
_API = {
    "load_space": "isu_validate.space",
    "open_renderer": "isu_validate.render",
    "load_camera": "capture.camera",
    "open_sut": "isu_validate.sut",
    "build_request": "isu_validate.sut",
    "make_judge": "isu_validate.evaluate",
    "PipelineConfig": "isu_validate.config",
    "RunConfig": "isu_validate.config",
    "run_search": "isu_validate.search",
    "tests_table": "isu_validate.archive.export",
    "report": "isu_validate.analysis",
    "plan_recreation": "isu_validate.recreate",
    "measure_agreement": "isu_validate.agree",
    "AgreeSettings": "isu_validate.agree",
    "build_dataset": "isu_validate.dataset",
    "DatasetSettings": "isu_validate.dataset",
    "replay_run": "isu_validate.replay",
    "ReplaySettings": "isu_validate.replay",
}
__all__ = sorted(_API)


__getattr__, __dir__ = lazy_names(__name__, _API)
