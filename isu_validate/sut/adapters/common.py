"""Small helpers the adapters share: option parsing and image encoding."""
from __future__ import annotations

import base64
import json
import mimetypes
import os
from pathlib import Path
from typing import Any, Mapping

from ..errors import SUTConfigError


def image_data_url(path: str | os.PathLike) -> str:
    return f"data:{media_type(path)};base64,{image_base64(path)}"


def image_base64(path: str | os.PathLike) -> str:
    return base64.b64encode(Path(path).read_bytes()).decode()


def media_type(path: str | os.PathLike) -> str:
    return mimetypes.guess_type(str(path))[0] or "image/png"


def take_options(options: Mapping[str, Any], known: Mapping[str, Any], where: str) -> dict[str, Any]:
    """``known`` maps option names to defaults; unknown names are a configuration error."""
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise SUTConfigError(f"{where}: unknown option(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    return {name: options.get(name, default) for name, default in known.items()}


def fingerprint(kind: str, ident: str, options: Mapping[str, Any]) -> str:
    return f"{kind}:{ident}:" + json.dumps(dict(options), sort_keys=True, default=str)


def number(value: Any, name: str, where: str, *, integer: bool = False) -> float | int | None:
    """Options arrive as strings from the command line."""
    if value is None or value == "":
        return None
    try:
        return int(value) if integer else float(value)
    except (TypeError, ValueError):
        raise SUTConfigError(f"{where}: option {name} must be a number, got {value!r}") from None



def http_client(opts: Mapping[str, Any], timeout_s: float, redactor, where: str):
    """The HTTP client with the rate limits and retry policy the adapter options ask for."""
    from ..http_client import HttpClient, RetryPolicy
    from ..limits import RateLimiter

    return HttpClient(
        timeout_s=timeout_s, redactor=redactor,
        limiter=RateLimiter(number(opts["max_concurrency"], "max_concurrency", where, integer=True),
                            number(opts["rpm"], "rpm", where)),
        retry=RetryPolicy(number(opts["max_retries"], "max_retries", where, integer=True),
                          number(opts["backoff_s"], "backoff_s", where),
                          number(opts["backoff_max_s"], "backoff_max_s", where),
                          number(opts["retry_after_max_s"], "retry_after_max_s", where)))
