"""Systems under test: one protocol, several adapters, repeats with majority vote, a response cache.

    sut = open_sut("openai:gpt-4o@https://api.openai.com/v1", space=space, repeats=3, cache_dir=run / "cache")
    response = sut.query(build_request(space, scene, image, "vqa"))

Modules: ``prompt`` (what is asked), ``adapters/`` (how: openai, command, http, reference),
``http_client`` + ``limits`` (retries, backoff, rate limits), ``parse`` (reading real VLM output),
``vote`` (majority over repeats), ``cache`` (replies on disk), ``runner`` (the SUT the search calls),
``registry`` (spec -> SUT), ``redact`` (keys never leave).
"""
from .errors import SUTConfigError, TransportError
from .prompt import DEFAULT_CAPTION_PROMPT, build_request, vqa_prompt
from .registry import ADAPTERS, open_sut, register_adapter
from .runner import RepeatingSUT, interpret

__all__ = ["ADAPTERS", "DEFAULT_CAPTION_PROMPT", "RepeatingSUT", "SUTConfigError", "TransportError",
           "build_request", "interpret", "open_sut", "register_adapter", "vqa_prompt"]
