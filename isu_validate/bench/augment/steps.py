"""The loop's steps through the real pipeline: random search (``run_search``), the dataset builder
(``build_dataset``), the retraining (``retrain_with_extra``), ``replay_run``, and the style: a stand-in
frame and a fast style net trained towards it. The tests hand ``run_augment`` doubles of these."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

SUT = "reference"


class PipelineSteps:
    def __init__(self, preset: str, pop_size: int, threshold: float, workdir: Path, log: Callable[[str], None]):
        self.preset, self.pop_size, self.threshold = preset, pop_size, threshold
        self.workdir, self.log = Path(workdir), log

    def search(self, run_dir: Path, seed: int, budget: int) -> dict:
        """A random-search run against the shipped reference ISU, judged at the bench's threshold."""
        from ...config import PipelineConfig, RunConfig
        from ...search.loop import run_search

        config = RunConfig(PipelineConfig(run_dir=str(run_dir), sut=SUT, preset=self.preset, threshold=self.threshold),
                           algorithm="rs", pop_size=self.pop_size, seed=seed, budget_tests=budget)
        summary = run_search(config, resume=(Path(run_dir) / "run.json").is_file())
        return {"run": str(run_dir), "tests": summary.tests, "failures": summary.failures, "renders": summary.tests}

    def verdicts(self, run_dir: Path) -> dict:
        """The run's per-feature verdicts (read back from its archive each time: cheap)."""
        from .unfixable import feature_verdicts

        return feature_verdicts(run_dir)

    def stand_in_frame(self, out: Path, seed: int) -> dict:
        """One stand-in frame (``capture shoot --source standin``'s: a seeded random scene rendered through
        another rig, under another sky, with sensor noise): not a photograph, and marked so in its sidecar."""
        import json

        import cv2
        import numpy as np

        from capture.sidecar import sidecar_path
        from capture.sources.standin import PRESET, StandInSource, standin_cabin
        from ...render import load_cabin, open_renderer
        from ...space import load_space

        space = load_space()
        scene = space.sample(np.random.default_rng(seed))[0]
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        with open_renderer(PRESET, camera="standin", cabin=standin_cabin(load_cabin("default")), space=space,
                           log_dir=out) as renderer:
            source = StandInSource("", lambda rig, path: renderer.render(scene, path).image, seed=seed)
            source.open()
            try:
                frame = source.read()
            finally:
                source.close()
        image = out / "standin.png"
        cv2.imwrite(str(image), frame.image)
        sidecar_path(image).write_text(json.dumps({**frame.meta, "scene": space.canonical(scene)}, indent=1))
        return {"image": str(image), "renders": 1}

    def train_style(self, style: Path, content_run: Path, out: Path, steps: int) -> dict:
        """A fast style net towards ``style``, trained on the renders of ``content_run`` (resumes itself)."""
        from style_transfer import FastTrainConfig, train_fast
        from ...image_files import IMAGE_SUFFIXES

        contents = sorted(p for p in (Path(content_run) / "images").iterdir()
                          if p.suffix in IMAGE_SUFFIXES and p.name.count(".") == 1)
        report = train_fast(Path(style), contents, Path(out), FastTrainConfig(steps=steps), resume=True)
        return {"model": str(out), "steps": report.steps_done, "final_loss": report.final_loss}

    def dataset(self, out: Path, n: int, seed: int, focus_run: Path | None, style: tuple[str, str] | None) -> dict:
        """N renders drawn uniformly, or near ``focus_run``'s failures; with ``style`` (image, fast net) each
        also gets a styled copy."""
        from ...dataset import DatasetSettings, build_dataset

        settings = DatasetSettings(n=n, seed=seed, preset=self.preset,
                                   from_runs=(str(focus_run),) if focus_run else (),
                                   focus="failing" if focus_run else None,
                                   styles=(style[0],) if style else (), style_models=(style[1],) if style else ())
        summary = build_dataset(settings, out, resume=(Path(out) / "dataset.json").is_file(), log=self.log)
        return {"dataset": str(out), "renders": summary.renders, "images": summary.images, "short": summary.short}

    def retrain(self, parts: list[tuple[Path, tuple[str, ...] | None]], out: Path) -> dict:
        """The shipped reference ISU retrained on its own features plus the datasets' images (of the variants
        named: ``render``, ``style1``; None: all)."""
        from ...dataset import open_dataset
        from ...reference.extra_data import extra_set
        from ...reference.model import default_model_dir
        from ...reference.retrain import retrain_with_extra
        from ...render import RENDERER_VERSION
        from ...space import load_space

        space = load_space()
        extra = []
        for folder, variants in parts:
            dataset = open_dataset(folder)
            extra.append(extra_set(folder, dataset.info(), dataset.metadata(), space, variants))
        card = retrain_with_extra(space, default_model_dir(), extra, out, RENDERER_VERSION,
                                  cache_dir=self.workdir / "features")
        return {"model": str(out), "change": card["change"], "comparison": card["comparison"],
                "extra_images": sum(len(part.images) for part in extra),
                "embed_seconds": card["embed_seconds"], "fit_seconds": card["fit_seconds"]}

    def replay(self, run_dir: Path, out: Path, model_dir: Path | None) -> dict:
        """The run's frames asked again of the reference ISU in ``model_dir`` (None: the shipped one)."""
        from ...replay import ReplaySettings, replay_run

        options = {"model_dir": str(model_dir)} if model_dir else {}
        result = replay_run(run_dir, out, ReplaySettings(sut=SUT, sut_options=options, threshold=self.threshold))
        summary = result.summary
        return {"rates": summary["rates"], "mcnemar": summary["mcnemar"], "per_feature": summary["per_feature"],
                "n_replayed": summary["n_replayed"], "sut_errors": summary["sut_errors"],
                "tests": [{k: row[k] for k in ("test_id", "f_qa_after", "became_right", "became_wrong")}
                          for row in result.rows]}
