"""POSTing JSON to a remote SUT: per-request deadline, retries with backoff and jitter, limits.

Retried: HTTP 429 and 5xx, connection failures and timeouts.  The wait before retry
``n`` (0-based) is ``min(backoff_max_s, backoff_s * 2**n)`` scaled by a random factor
in [0.5, 1] (jitter, so parallel workers do not retry in lockstep); a ``Retry-After``
header (seconds or an HTTP date) replaces it, capped at ``retry_after_max_s``.
Not retried: other 4xx.  401/403 raise SUTConfigError (the key is wrong for every
scene); other failures raise TransportError, which the caller records as a SUT error.
Every message passes through the redactor: no API key reaches a log or the archive.
"""
from __future__ import annotations

import email.utils
import json
import random
import time
from dataclasses import dataclass
from typing import Any, Callable

import requests

from .errors import SUTConfigError, TransportError
from .limits import RateLimiter
from .redact import Redactor
from ..errors import InputError

RETRY_STATUS = {429, 500, 502, 503, 504, 529}
_BODY_SHOWN = 300


@dataclass
class HttpReply:
    status: int
    text: str
    latency_s: float
    attempts: int

    def json(self) -> Any:
        return json.loads(self.text)


@dataclass
class RetryPolicy:
    max_retries: int = 4
    backoff_s: float = 1.0
    backoff_max_s: float = 30.0
    retry_after_max_s: float = 120.0

    def delay(self, attempt: int, retry_after: float | None, rng: random.Random) -> float:
        if retry_after is not None:
            return min(max(retry_after, 0.0), self.retry_after_max_s)
        return min(self.backoff_max_s, self.backoff_s * 2 ** attempt) * rng.uniform(0.5, 1.0)


def parse_retry_after(value: str | None, now: float | None = None) -> float | None:
    if not value:
        return None
    value = value.strip()
    try:
        return max(float(value), 0.0)
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    return max(when.timestamp() - (now if now is not None else time.time()), 0.0)


class HttpClient:
    def __init__(self, *, timeout_s: float = 60.0, retry: RetryPolicy | None = None,
                 limiter: RateLimiter | None = None, redactor: Redactor | None = None,
                 sleep: Callable[[float], None] = time.sleep, seed: int | None = None):
        if timeout_s <= 0:
            raise InputError(f"timeout_s must be positive, got {timeout_s}")
        self.timeout_s = timeout_s
        self.retry = retry or RetryPolicy()
        self.limiter = limiter or RateLimiter()
        self.redact = redactor or Redactor()
        self._sleep = sleep
        self._rng = random.Random(seed)
        self.session = requests.Session()

    def post_json(self, url: str, payload: Any, headers: dict[str, str] | None = None) -> HttpReply:
        """The final successful reply (2xx); raises TransportError or SUTConfigError."""
        body = json.dumps(payload).encode()
        headers = {"Content-Type": "application/json", **(headers or {})}
        start = time.perf_counter()
        for attempt in range(self.retry.max_retries + 1):
            last = attempt == self.retry.max_retries
            try:
                with self.limiter.slot():
                    status, text, resp_headers = self._post_once(url, body, headers)
            except TransportError as exc:  # timeout or connection failure
                if last:
                    raise TransportError(f"{exc} (gave up after {attempt + 1} attempts)",
                                         attempts=attempt + 1) from None
                self._sleep(self.retry.delay(attempt, None, self._rng))
                continue
            if 200 <= status < 300:
                return HttpReply(status, text, time.perf_counter() - start, attempt + 1)
            message = self._http_message(url, status, text)
            if status in (401, 403):
                raise SUTConfigError(f"{message}; check the API key (its environment variable) and its access")
            if status not in RETRY_STATUS:
                raise TransportError(message, status=status, attempts=attempt + 1)
            if last:
                raise TransportError(f"{message} (gave up after {attempt + 1} attempts)",
                                     status=status, attempts=attempt + 1)
            self._sleep(self.retry.delay(attempt, parse_retry_after(resp_headers.get("Retry-After")), self._rng))
        raise AssertionError("unreachable")

    def _post_once(self, url: str, body: bytes, headers: dict) -> tuple[int, str, dict]:
        """One POST whose whole exchange (connect, wait, body) ends by the deadline."""
        deadline = time.monotonic() + self.timeout_s
        try:
            with self.session.post(url, data=body, headers=headers, stream=True,
                                   timeout=(min(10.0, self.timeout_s), self.timeout_s)) as resp:
                chunks = []
                for chunk in resp.iter_content(65536):
                    chunks.append(chunk)
                    if time.monotonic() > deadline:
                        raise requests.Timeout("reply body still arriving at the deadline")
                text = b"".join(chunks).decode(resp.encoding or "utf-8", errors="replace")
                return resp.status_code, self.redact(text), dict(resp.headers)
        except requests.Timeout:
            raise TransportError(f"timed out after {self.timeout_s:g} s waiting for {self._where(url)}") from None
        except requests.RequestException as exc:
            reason = self.redact(str(exc))[:_BODY_SHOWN]
            raise TransportError(f"cannot reach {self._where(url)}: {type(exc).__name__}: {reason}") from None

    def _where(self, url: str) -> str:
        return self.redact(url.split("?", 1)[0])

    def _http_message(self, url: str, status: int, text: str) -> str:
        detail = text.strip().replace("\n", " ")[:_BODY_SHOWN]
        return f"HTTP {status} from {self._where(url)}: {json.dumps(detail, ensure_ascii=False)}"

    def close(self) -> None:
        self.session.close()
