"""Systems under test: one protocol, several adapters, repeats with majority vote, a response cache.

    sut = open_sut("openai:gpt-4o@https://api.openai.com/v1", space=space, repeats=3, cache_dir=run / "cache")
    response = sut.query(build_request(space, scene, image, "vqa"))

Modules: ``prompt`` (what is asked), ``adapters/`` (how: openai, command, http, reference),
``http_client`` + ``limits`` (retries, backoff, rate limits), ``parse`` (reading real VLM output),
``vote`` (majority over repeats), ``cache`` (replies on disk), ``runner`` (the SUT the search calls),
``registry`` (spec -> SUT), ``redact`` (keys never leave).
"""
from __future__ import annotations

from ..lazy import lazy_names
from .errors import SUTConfigError, TransportError

# the rest loads on first use (PEP 562): the command line reads ``prompt``'s styles for --help
# without loading the adapters. public name -> the submodule it lives in
_NAMES = {"DEFAULT_CAPTION_PROMPT": ".prompt", "build_request": ".prompt", "vqa_prompt": ".prompt",
          "ADAPTERS": ".registry", "open_sut": ".registry", "register_adapter": ".registry",
          "RepeatingSUT": ".runner", "interpret": ".runner",
          "query_guarded": ".runner"}

__all__ = ["ADAPTERS", "DEFAULT_CAPTION_PROMPT", "RepeatingSUT", "SUTConfigError", "TransportError",
           "build_request", "interpret", "open_sut", "query_guarded", "register_adapter", "vqa_prompt"]


__getattr__, __dir__ = lazy_names(__name__, _NAMES)
