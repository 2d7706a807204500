"""The SUT the search talks to: an adapter, asked K times per scene, through the response cache.

Each repeat's reply is parsed on its own (``interpret``); VQA repeats are combined by
per-feature majority vote (``vote.majority``), captions are all kept (the judge scores
each and averages).  The whole response is a SUT error only when every repeat failed.
"""
from __future__ import annotations

import time
import traceback
from typing import Any

from ..protocols import SUTRequest, SUTResponse
from .cache import ResponseCache
from .exchange import Adapter, Exchange
from .parse import OUTCOME_ANSWERED, OUTCOME_ERROR, OUTCOME_PARTIAL, parse_caption, parse_vqa
from .vote import majority
from ..errors import InputError


def interpret(request: SUTRequest, exchange: Exchange) -> SUTResponse:
    """One reply -> answers or caption, problems, and the outcome (answered/partial/error)."""
    response = SUTResponse(raw=exchange.raw, latency_s=exchange.latency_s, extra={"meta": dict(exchange.meta)})
    if exchange.error:
        response.error = exchange.error
        response.extra["outcome"] = OUTCOME_ERROR
        return response
    if request.mode == "vc":
        parsed = parse_caption(exchange.content)
        response.caption, response.error, response.problems = parsed.caption, parsed.error, list(parsed.problems)
        response.extra["outcome"] = OUTCOME_ERROR if parsed.error else OUTCOME_ANSWERED
        return response
    parsed = parse_vqa(exchange.content, request.questions)
    response.error, response.problems = parsed.error, list(parsed.problems)
    response.answers = None if parsed.error else dict(parsed.answers)
    response.extra.update(outcome=parsed.outcome, status=dict(parsed.status), notes=list(parsed.notes),
                          ignored_keys=list(parsed.ignored_keys))
    return response


def query_guarded(sut, request: SUTRequest) -> SUTResponse:
    """``sut.query(request)``, with an adapter's bug on one request turned into a SUT error response (a
    run, replay or agreement must not end on it); a ValueError is a configuration problem (a rejected
    key) that no later request would escape, and is raised."""
    try:
        return sut.query(request)
    except ValueError:
        raise
    except Exception as exc:
        return SUTResponse(error=f"{type(exc).__name__}: {exc}", raw=traceback.format_exc(limit=3))


class RepeatingSUT:
    """Implements the ``SUT`` protocol on top of an adapter."""

    def __init__(self, adapter: Adapter, *, repeats: int = 1, cache: ResponseCache | None = None):
        if repeats < 1:
            raise InputError(f"repeats must be at least 1, got {repeats}")
        self.adapter, self.repeats, self.cache = adapter, repeats, cache
        self.id = adapter.id

    def query(self, request: SUTRequest) -> SUTResponse:
        start = time.perf_counter()
        runs = [self._once(request, i) for i in range(self.repeats)]
        combined = runs[0] if self.repeats == 1 else self._combine(request, runs)
        combined.latency_s = time.perf_counter() - start  # what this query cost now (cache hits are free)
        combined.extra["sut_latency_s"] = [r.latency_s for r in runs]
        combined.extra["cached"] = [bool(r.extra.get("cached")) for r in runs]
        return combined

    def _once(self, request: SUTRequest, repeat: int) -> SUTResponse:
        key = self.cache.key(request, self.adapter.fingerprint, repeat) if self.cache else None
        entry = self.cache.get(key) if key else None
        if entry is not None:
            exchange = Exchange(raw=entry["raw"], content=entry["content"], latency_s=entry["latency_s"],
                                meta=entry.get("meta", {}))
        else:
            exchange = self.adapter.send(request)
            if key and exchange.error is None:
                self.cache.put(key, {"sut": self.id, "repeat": repeat, "raw": exchange.raw,
                                     "content": exchange.content, "latency_s": exchange.latency_s,
                                     "meta": exchange.meta, "created": time.time()})
        response = interpret(request, exchange)
        response.extra["cached"] = entry is not None
        return response

    def _combine(self, request: SUTRequest, runs: list[SUTResponse]) -> SUTResponse:
        ok = [r for r in runs if not r.error]
        per_repeat = [{"raw": r.raw, "answers": r.answers, "caption": r.caption, "error": r.error,
                       "problems": r.problems, "latency_s": r.latency_s} for r in runs]
        extra: dict[str, Any] = {"repeats": self.repeats, "per_repeat": per_repeat, "errors": len(runs) - len(ok)}
        first = ok[0] if ok else runs[0]
        if not ok:
            return SUTResponse(raw=first.raw, error=f"all {self.repeats} repeats failed; first: {first.error}",
                               extra={**extra, "outcome": OUTCOME_ERROR})
        if request.mode == "vc":
            extra.update(outcome=OUTCOME_ANSWERED, captions=[r.caption for r in ok])
            return SUTResponse(raw=first.raw, caption=first.caption, problems=list(first.problems), extra=extra)
        keys = [q.key for q in request.questions]
        vote = majority(keys, [(r.answers or {}, r.extra.get("status", {})) for r in runs])
        problems = [f"{k}: {s} in every repeat" for k, s in vote.status.items() if s != "answered"]
        problems += [f"{k}: tie between {', '.join(v)} across repeats; kept {v[0]} (given first)"
                     for k, v in vote.ties.items()]
        outcome = OUTCOME_ANSWERED if len(vote.answers) == len(keys) else OUTCOME_PARTIAL
        extra.update(outcome=outcome, status=vote.status, consistency=vote.consistency,
                     unanimous=vote.unanimous, consistency_by_feature=vote.by_feature, ties=vote.ties)
        return SUTResponse(raw=first.raw, answers=vote.answers, problems=problems, extra=extra)

    def close(self) -> None:
        close = getattr(self.adapter, "close", None)
        if close:
            close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
