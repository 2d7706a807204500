"""Does the new SUT's model know the run's scene space? A model trained for another space answers
about other features (or the same names with other meanings), so its answers judge nothing.

A model that records the space it was trained for says so in its metadata: the reference ISU's
``heads.json`` holds ``space`` and ``space_hash`` (``reference train`` writes them), and its adapter
keeps the model as ``adapter.model``. SUTs that record nothing (a VLM behind an API) are not checked.
"""
from __future__ import annotations

from ..errors import InputError


def model_space(sut) -> dict | None:
    """``{"space", "space_hash", "model"}`` of the model behind ``sut`` where it records them, else None."""
    model = getattr(getattr(sut, "adapter", None), "model", None)
    meta = getattr(model, "meta", None)
    if not isinstance(meta, dict) or not meta.get("space_hash"):
        return None
    return {"space": meta.get("space"), "space_hash": str(meta["space_hash"]),
            "model": str(getattr(model, "model_dir", "") or "")}


def check_covers(sut, spec: str, run_path, space_name: str, space_hash: str) -> None:
    """Refuse a SUT whose model was trained for another scene space than the run's, naming both."""
    trained = model_space(sut)
    if trained is None or trained["space_hash"] == space_hash:
        return
    where = f" in {trained['model']}" if trained["model"] else ""
    raise InputError(
        f"the SUT {spec!r} does not cover the run's scene space: its model{where} was trained for the space "
        f"{trained['space']!r} (hash {trained['space_hash']}), the run {run_path} is of the space {space_name!r} "
        f"(hash {space_hash}); replay it with a model trained for that space "
        f"(isu-validate reference train --space ..., then --sut-option model_dir=...)")
