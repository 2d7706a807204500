"""The reference ISU: backbone features -> one head per feature -> answers and captions."""
from __future__ import annotations

import hashlib
from pathlib import Path


from ..paths import data_dir
from ..space import SceneSpace
from .backbone import Backbone, read_rgb
from .captioner import describe
from .heads import load_heads, load_window_heads
from .detector import FrameDetector, open_in_model
from .stacking import Stacking
from .windows import WindowSettings, frame_probabilities
from ..errors import InputError


def default_model_dir() -> Path:
    return data_dir() / "reference-isu"


def backbone_of(model_dir: Path, meta: dict, device: str = "auto") -> Backbone:
    """The backbone a model's heads were fitted on: frozen, or tuned with the weights beside the heads (checked
    against the name its features were made with, so that another model's weights are never read by these heads)."""
    weights = meta.get("backbone_weights")
    backbone = Backbone(*meta.get("input_size", [320, 240]), device=device,
                        tuned=Path(model_dir) / weights if weights else None)
    if weights and backbone.name != meta.get("backbone"):
        raise InputError(f"the tuned backbone {Path(model_dir) / weights} is not the one the heads in {model_dir} "
                         f"were fitted on ({meta.get('backbone')}, not {backbone.name}); copy the model folder whole, "
                         "or train the model again")
    return backbone


def detector_of(model_dir: Path, meta: dict) -> FrameDetector | None:
    """The detector a model's window heads are stacked with (None for a model without one), checked against the
    digest its stacking was fitted with."""
    about = (meta.get("windows") or {}).get("detector")
    if not about:
        return None
    detector = open_in_model(Path(model_dir), about)
    if detector.detector.sha256 != about["sha256"]:
        raise InputError(f"{Path(model_dir) / about['file']} is not the detector the model in {model_dir} was fitted "
                         f"with (sha256 {detector.detector.sha256[:12]}, not {about['sha256'][:12]}); copy the model "
                         "folder whole, or train the model again")
    return detector


class ReferenceISU:
    def __init__(self, space: SceneSpace, model_dir: Path | None = None, backbone: Backbone | None = None,
                 device: str = "auto"):
        self.space = space
        self.model_dir = Path(model_dir or default_model_dir())
        heads, self.meta = load_heads(self.model_dir)
        self.heads = {h.feature: h for h in heads}
        unknown = set(self.heads) - set(space.names)
        if unknown:
            raise InputError(f"the reference ISU in {self.model_dir} was trained for features {sorted(unknown)} "
                             f"that space {space.name!r} does not have; retrain it for this space")
        self.backbone = backbone or backbone_of(self.model_dir, self.meta, device)
        # window heads (windows.py) answer their features in place of the whole-frame heads
        self.window_heads = load_window_heads(self.model_dir, self.meta)
        self.windows = WindowSettings.from_meta(self.meta["windows"]) if self.window_heads else None
        self.calibration = {name: Stacking.from_meta(value)
                            for name, value in self.meta["windows"]["calibration"].items()} if self.windows else {}
        self.detector = detector_of(self.model_dir, self.meta)   # stacked with the window heads, where trained so

    def predict(self, image: Path) -> dict[str, str]:
        """An answer for every feature it has a head for; NONE where its own answers say the
        thing is absent (no luggage seen -> no luggage colour)."""
        return self.read(image)[0]

    def read(self, image: Path) -> tuple[dict[str, str], dict[str, dict[str, float]]]:
        """(answers as ``predict`` gives them, each head's class probabilities): the probabilities are what
        a ROC curve of the model needs (``transfer``'s AUC); the answers are their argmax, made NONE as above."""
        rgb = read_rgb(image)
        features = self.backbone.features([rgb])
        probabilities = {name: dict(zip(head.classes, map(float, head.probabilities(features)[0]), strict=True))
                         for name, head in self.heads.items()}
        if self.windows:
            maps = self.windows.maps(self.backbone, rgb)
            seen = self.detector.log_odds(rgb, [h.feature for h in self.window_heads]) if self.detector else None
            probabilities.update(frame_probabilities(self.window_heads, self.calibration, maps, seen))
        raw = {name: max(p, key=p.get) for name, p in probabilities.items()}
        answers = {name: (answer if self._active(name, raw) else "NONE") for name, answer in raw.items()}
        return answers, probabilities

    def _active(self, name: str, answers: dict[str, str]) -> bool:
        condition = self.space.features[name].active_when
        if condition is None:
            return True
        seen = {n: answers.get(n, "NONE") for n in condition.features if n in self.heads}
        if len(seen) < len(condition.features):
            return True  # depends on something it cannot see: answer anyway
        return condition.matches(seen)

    def answer(self, image: Path, keys: list[str]) -> dict[str, str]:
        predictions = self.predict(image)
        return {k: predictions[k] for k in keys if k in predictions}

    def caption(self, image: Path) -> str:
        predictions = self.predict(image)
        variant = int(hashlib.sha1(Path(image).read_bytes()).hexdigest(), 16)
        return describe(predictions, variant)
