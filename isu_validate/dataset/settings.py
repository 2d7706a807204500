"""What a dataset is made of: ``DatasetSettings``, recorded in ``dataset.json``; a ``--resume`` with other
settings is refused with every difference named (as ``run.json`` does for runs).

A light module (no numpy): the command line reads its defaults for ``--help``.
"""
from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from ..errors import InputError

FOCUS_MODES = ("failing", "passing")
RULE_PREFIX = "rule:"
# the variety a command takes (--camera-jitter, --sensor-effects, --camera-mix; `dataset`, `reference train`): off,
# they are left out of an output's identity, so datasets and models made before them resume
VARIETY = ("camera_jitter", "sensor_effects", "camera_mix")
# how the work is spread: may change between a start and its --resume
NOT_IDENTITY = ("workers", "cluster", "render_device", "device")   # how the work is done: a resume may change them


@dataclass(frozen=True)
class DatasetSettings:
    """Everything that decides a dataset's images (the work spreading aside: ``workers``, ``cluster``).

    ``preset`` is a preset name or, for tests and benchmarks, a ``render.Preset``; ``focus`` is None
    (scenes drawn uniformly from the space), ``failing``, ``passing`` or ``rule:TEXT`` with ``from_runs``.
    ``styles``: style images, each giving every render a style-transferred copy (the fast net of
    ``style_models`` trained for that image, else Gatys at ``style_size`` px and ``style_steps``).
    ``camera_jitter``, ``sensor_effects`` and ``camera_mix``: variety per scene (``render/variety.py``), drawn from
    ``seed`` and the scene; "" (the default) renders every slot through the camera file's camera, untouched.
    ``renderer_factory`` (``module:function``, called with the space) replaces Blender, for tests.

        settings = DatasetSettings(n=200, seed=1, preset="draft", from_runs=("runs/s1",), focus="failing")
        build_dataset(settings, "datasets/near-failures")"""
    n: int = 100
    seed: int = 0
    space: str = "isu-paper"
    preset: Any = "draft"
    camera: str = "default"
    extrinsics_from: str | None = None
    cabin: str = "default"
    prompt_style: str = "paper"
    from_runs: tuple[str, ...] = ()
    focus: str | None = None
    styles: tuple[str, ...] = ()
    style_models: tuple[str, ...] = ()
    style_size: int = 192
    style_steps: int = 40
    camera_jitter: str = ""       # e.g. "pos=0.05,angle=5,focal=0.1" (render/camera_jitter.py)
    sensor_effects: str = ""      # e.g. "mild" or "noise=0.02,jpeg=0.5" (render/sensor_effects.py)
    camera_mix: str = ""          # e.g. "default,passenger-door": rigs a slot may be seen through (render/variety.py)
    renderer_factory: str = ""
    workers: int = 1
    cluster: str | None = None
    render_device: str = "auto"   # Cycles' compute device (render/gpu.py)
    device: str = "auto"          # where the style transfer's torch work runs (devices.py)
    inputs: dict = field(default_factory=dict, compare=False)   # digests of runs and style files (identity)

    def check(self) -> DatasetSettings:
        """Problems a user can fix, before anything is read or written; the settings with paths made absolute
        and the focus defaulted (``failing`` when runs are given)."""
        if self.n < 1:
            raise InputError(f"--n must be at least 1 (images to render), got {self.n}")
        if self.workers < 1:
            raise InputError(f"--workers must be at least 1, got {self.workers}")
        if self.style_size < 16 or self.style_steps < 1:
            raise InputError("--style-size must be at least 16 px and --style-steps at least 1")
        focus = self.focus or ("failing" if self.from_runs else None)
        if focus is not None and focus not in FOCUS_MODES and not focus.startswith(RULE_PREFIX):
            raise InputError(f"unknown --focus {focus!r}; use failing, passing or rule:\"FEATURE = VALUE and ...\"")
        if focus in FOCUS_MODES and not self.from_runs:
            raise InputError(f"--focus {focus} needs --from-run RUN... (the runs whose {focus} tests to focus on)")
        if self.style_models and not self.styles:
            raise InputError("--style-model needs --style IMG (the style images the models were trained for)")
        variety = self.variety()
        return replace(self, focus=focus, camera_jitter=variety.jitter.text, sensor_effects=variety.effects.text,
                       camera_mix=",".join(_rig(name) for name in variety.cameras),
                       from_runs=_absolute(self.from_runs), styles=_absolute(self.styles),
                       style_models=_absolute(self.style_models), space=_rig(self.space), camera=_rig(self.camera),
                       cabin=_rig(self.cabin), extrinsics_from=_rig(self.extrinsics_from))

    def variety(self):
        """The per-scene camera jitter, sensor effects and camera mix (``render.variety.Variety``); InputError for a
        bad spec."""
        from ..render.variety import Variety
        return Variety.parse(self.camera_jitter, self.sensor_effects, self.seed, self.camera_mix)

    def to_dict(self) -> dict:
        out = asdict(self)
        out.update(from_runs=list(self.from_runs), styles=list(self.styles), style_models=list(self.style_models))
        if not isinstance(self.preset, str):   # a Preset: its parameters
            out["preset"] = asdict(self.preset)
        return out

    @classmethod
    def from_dict(cls, data: dict) -> DatasetSettings:
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in data.items() if k in known}
        for name in ("from_runs", "styles", "style_models"):
            values[name] = tuple(values.get(name) or ())
        if isinstance(values.get("preset"), dict):
            from ..render.presets import Preset
            values["preset"] = Preset(**values["preset"])
        return cls(**values)

    def identity(self) -> dict:
        """The settings a resume must match (the inputs' digests included)."""
        out = self.to_dict()
        for name in NOT_IDENTITY:
            out.pop(name)
        for name in VARIETY:
            if not out[name]:
                out.pop(name)
        return out

    @property
    def preset_name(self) -> str:
        return self.preset if isinstance(self.preset, str) else self.preset.name


def differences(stored: dict, given: dict) -> list[str]:
    """``name: stored -> given`` for every identity setting that differs."""
    return [f"{k}: {stored.get(k)!r} (stored) vs {given.get(k)!r} (given)"
            for k in sorted(set(stored) | set(given)) if stored.get(k) != given.get(k)]


def file_digest(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def _absolute(paths) -> tuple[str, ...]:
    return tuple(str(Path(p).resolve()) for p in paths)


def _rig(name: str | None) -> str | None:
    """A rig given as a .toml path, made absolute (a resume from another folder means the same file); a
    shipped rig's name stays a name."""
    return str(Path(name).resolve()) if name and str(name).endswith(".toml") else name
