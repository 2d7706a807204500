"""``bench:NAME``: a benchmark SUT with known blind spots (``isu_validate.sut.planted``).

It answers from the scene, not the image: inside a run directory the scene of
``images/<test>.png`` is in ``labels/<test>.json``, written before the image is rendered.
So a run with ``--sut bench:blind-spots`` renders for real (its cost, its artefacts)
while the SUT's errors are the ones the benchmark planted; outside a run it has no
scene to read and says so.
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from ...archive.run_dir import RunDir
from ...protocols import SUTRequest
from ..errors import SUTConfigError
from ..exchange import Exchange
from .common import fingerprint, take_options


class BenchmarkAdapter:
    def __init__(self, target: str, *, timeout_s: float = 60.0, space=None, **options: Any):
        from ..planted import make_benchmark_sut

        take_options(options, {}, f"SUT bench:{target}")
        try:
            self.sut = make_benchmark_sut(target, space)
        except ValueError as exc:
            raise SUTConfigError(f"SUT bench:{target}: {exc}") from None
        self.space = space
        self.id = f"bench:{target}"
        self.fingerprint = fingerprint("bench", self.id, {"spots": [s.name for s in self.sut.blind_spots],
                                                          "noise": self.sut.noise, "space": space.hash})

    def send(self, request: SUTRequest) -> Exchange:
        start = time.perf_counter()
        image = Path(request.image)
        label = RunDir(image.parent.parent).label_file(image.stem)   # the run's images/ and labels/
        if request.mode != "vqa":
            return Exchange(error=f"{self.id} answers questions only (mode vqa), not {request.mode!r}")
        try:
            scene = json.loads(label.read_text())["scene"]
        except (OSError, ValueError, KeyError) as exc:
            return Exchange(error=f"{self.id} answers from the scene label {label} beside the image, which cannot be "
                                  f"read ({exc}); benchmark SUTs work only inside runs (isu-validate run / bench)")
        answers = self.sut.answer(self.space, scene)
        content = {"answers": answers}
        return Exchange(raw=json.dumps(content), content=content, latency_s=time.perf_counter() - start)

    def close(self) -> None:
        pass


def open_benchmark(target: str, **kwargs: Any) -> BenchmarkAdapter:
    return BenchmarkAdapter(target, **kwargs)
