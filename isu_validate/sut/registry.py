"""``--sut SPEC`` -> a SUT: the spec's scheme picks the adapter.

Specs (a contract, see docs/ARCHITECTURE.md): ``reference``, ``openai:MODEL@BASE_URL``,
``command:PROGRAM ARGS...``, ``http:URL``; and for benchmarking searches ``bench:NAME``
(a SUT with planted blind spots that answers from the run's scene labels).  Plugging in a new kind of SUT is one
line in ``ADAPTERS`` (or ``register_adapter`` at import time).
"""
from __future__ import annotations

import os
from typing import Any, Callable

from ..space import SceneSpace
from .adapters.benchmark import open_benchmark
from .adapters.command import open_command
from .adapters.http_json import open_http
from .adapters.openai_chat import open_openai
from .adapters.reference import open_reference
from .cache import ResponseCache
from .errors import SUTConfigError
from .runner import RepeatingSUT

# scheme -> factory(target, *, timeout_s, space, **options) -> adapter
ADAPTERS: dict[str, Callable[..., Any]] = {
    "reference": open_reference,
    "openai": open_openai,
    "command": open_command,
    "http": open_http,
    "bench": open_benchmark,
}
USAGE = {"reference": "reference", "openai": "openai:MODEL@BASE_URL", "command": "command:PROGRAM ARGS...",
         "http": "http:URL", "bench": "bench:NAME"}
# Factories that want the scene space (the reference ISU's heads are per feature).
NEEDS_SPACE = {"reference", "bench"}
NEEDS_DEVICE = {"reference"}   # adapters that run torch here: they take the one --device setting


def register_adapter(scheme: str, factory: Callable[..., Any], *, needs_space: bool = False) -> None:
    ADAPTERS[scheme] = factory
    if needs_space:
        NEEDS_SPACE.add(scheme)


def split_spec(spec: str) -> tuple[str, str]:
    scheme, _, target = spec.strip().partition(":")
    if scheme not in ADAPTERS:
        raise SUTConfigError(f"unknown SUT spec {spec!r}; use one of: reference, openai:MODEL@BASE_URL, "
                             "command:PROGRAM ARGS..., http:URL")
    return scheme, target.strip()


def open_sut(spec: str, *, space: SceneSpace, repeats: int = 1, cache_dir: str | os.PathLike | None = None,
             timeout_s: float = 60.0, device: str = "auto", **options: Any) -> RepeatingSUT:
    """The SUT for ``spec``, asked ``repeats`` times per scene (majority vote), replies cached under
    ``cache_dir`` (none when None); ``device``: where an embedded SUT's torch work runs (``devices.py``).
    Raises SUTConfigError naming the problem and the fix.

        with open_sut("reference", space=space) as sut:       # or "openai:gpt-4o@https://api.openai.com/v1"
            response = sut.query(build_request(space, scene, "scene.png", "vqa"))
    """
    scheme, target = split_spec(spec)
    if scheme != "reference" and not target:
        raise SUTConfigError(f"SUT spec {spec!r} names nothing after '{scheme}:'; "
                             f"write {USAGE.get(scheme, scheme + ':...')}")
    if timeout_s <= 0:
        raise SUTConfigError(f"SUT timeout must be positive, got {timeout_s}")
    extra = {"space": space} if scheme in NEEDS_SPACE else {}
    if scheme in NEEDS_DEVICE:
        extra["device"] = device
    adapter = ADAPTERS[scheme](target, timeout_s=timeout_s, **extra, **options)
    cache = ResponseCache(cache_dir) if cache_dir is not None else None
    return RepeatingSUT(adapter, repeats=int(repeats), cache=cache)
