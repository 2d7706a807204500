"""Which version of a SUT gave a result: what a replay (v1 against v2 on the same scenes) names wherever it
shows one. An adapter may say what identifies its model (``model_version``: the reference ISU's folder and
heads hash, an API's model name); every adapter has a fingerprint, shown as a short digest."""
from __future__ import annotations

import hashlib


def sut_version(spec: str, adapter) -> dict:
    """``{"spec", "model", "fingerprint", "label"}``; the label reads e.g.
    ``reference (model runs/m2, heads 1a2b3c4d5e6f; fingerprint 0f1e2d3c4b5a)``."""
    model = getattr(adapter, "model_version", None)
    digest = hashlib.sha256(adapter.fingerprint.encode()).hexdigest()[:12]
    label = f"{spec} ({model}; fingerprint {digest})" if model else f"{spec} (fingerprint {digest})"
    return {"spec": spec, "model": model, "fingerprint": digest, "label": label}
