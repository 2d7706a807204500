"""One round trip to a SUT, before any parsing; what every adapter returns."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from ..protocols import SUTRequest


@dataclass
class Exchange:
    raw: str = ""                 # the reply verbatim (redacted): chat content, command stdout, HTTP body
    content: Any = None           # what to parse: text, or the decoded JSON object the protocol defines
    error: str | None = None      # transport error (timeout, HTTP failure, crash): a SUT error, never cached
    latency_s: float = 0.0
    meta: dict[str, Any] = field(default_factory=dict)  # e.g. http status, attempts, finish_reason


class Adapter(Protocol):
    """Talks to one kind of SUT.  ``fingerprint`` names everything that changes its answers
    (model, endpoint, answer-affecting options; never secrets): it keys the response cache."""
    id: str
    fingerprint: str

    def send(self, request: SUTRequest) -> Exchange: ...

    def close(self) -> None: ...
