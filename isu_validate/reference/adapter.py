"""``--sut reference``: the reference ISU behind the same adapter seam as every SUT."""
from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any

from ..protocols import SUTRequest
from ..sut.adapters.common import fingerprint, take_options
from ..sut.errors import SUTConfigError
from ..sut.exchange import Exchange
from .model import ReferenceISU, default_model_dir

OPTIONS = {"model_dir": None}


class ReferenceAdapter:
    def __init__(self, target: str = "", *, timeout_s: float = 60.0, space=None, device: str = "auto",
                 **options: Any):
        opts = take_options(options, OPTIONS, "SUT reference")
        model_dir = Path(opts["model_dir"] or default_model_dir())
        try:
            self.model = ReferenceISU(space, model_dir, device=device)
        except (FileNotFoundError, ValueError) as exc:
            raise SUTConfigError(f"SUT reference: {exc}") from None
        self.id = "reference"
        self.device = self.model.backbone.device.describe()   # where its torch work runs (summaries name it)
        heads = hashlib.sha1((model_dir / "heads.npz").read_bytes()).hexdigest()[:12]
        clip = self.model.meta.get("clip_sigma")    # how the heads read features; absent before clipping,
        windows = self.model.meta.get("windows")     # and how window heads read frames (their calibration too),
        self.fingerprint = fingerprint("reference", self.id,   # so older models keep their fingerprints
                                       {"heads": heads, **({"clip_sigma": clip} if clip is not None else {}),
                                        **({"windows": windows} if windows else {})})
        self.model_version = f"model {model_dir.resolve()}, heads {heads}"   # what a replay names

    def send(self, request: SUTRequest) -> Exchange:
        start = time.perf_counter()
        try:
            meta = {}
            if request.mode == "vqa":
                keys = [q.key for q in request.questions]
                answers, probabilities = self.model.read(Path(request.image))
                content = {"answers": {k: answers[k] for k in keys if k in answers}}
                # the heads' class probabilities, beside the reply (never in it): what an AUC needs
                meta["probabilities"] = {k: probabilities[k] for k in keys if k in probabilities}
            else:
                content = {"caption": self.model.caption(Path(request.image))}
        except (OSError, ValueError) as exc:
            return Exchange(error=f"reference ISU could not read the image: {exc}",
                            latency_s=time.perf_counter() - start)
        return Exchange(raw=json.dumps(content), content=content, latency_s=time.perf_counter() - start, meta=meta)
