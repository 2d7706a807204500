"""``openai:MODEL@BASE_URL``: any OpenAI-compatible chat-completions API.

Covers OpenAI and Azure OpenAI, Gemini's OpenAI-compatible endpoint, vLLM, Ollama,
llama.cpp and LM Studio (Moondream2 or any local VLM).  The image goes as a base64
data URL.  The API key is read from the environment variable named by
``api_key_env`` (default ``OPENAI_API_KEY``) when the SUT is opened and is never
stored, logged or cached; a local server without a key gets no Authorization header.

Options (``--sut-option NAME=VALUE``):
  api_key_env      environment variable holding the key (default OPENAI_API_KEY)
  auth             "bearer" (default) or "api-key" (Azure's header)
  api_version      appended as ?api-version=... (Azure)
  json_mode        "auto" (default: ask for a JSON object in VQA, drop it if the server refuses),
                   "on", or "off"
  temperature, max_tokens, detail (image detail: low/high/auto)   sent only when given
  max_concurrency  parallel requests per process (default 4); rpm: requests per minute
  max_retries, backoff_s, backoff_max_s, retry_after_max_s       see http_client
"""
from __future__ import annotations

import os
import re
import threading
from typing import Any
from urllib.parse import urlparse

from ...protocols import SUTRequest
from ..errors import SUTConfigError, TransportError
from ..exchange import Exchange
from ..redact import Redactor
from .common import fingerprint, http_client, image_data_url, take_options

DEFAULT_BASE_URL = "https://api.openai.com/v1"
# Hosts that always need a key: fail at open time, not once per scene.
_KEYED_HOSTS = ("api.openai.com", "openai.azure.com", "generativelanguage.googleapis.com")
OPTIONS = {"api_key_env": "OPENAI_API_KEY", "auth": "bearer", "api_version": None, "json_mode": "auto",
           "temperature": None, "max_tokens": None, "detail": None, "max_concurrency": 4, "rpm": None,
           "max_retries": 4, "backoff_s": 1.0, "backoff_max_s": 30.0, "retry_after_max_s": 120.0}
_ANSWER_OPTIONS = ("temperature", "max_tokens", "detail", "json_mode")


def parse_target(target: str) -> tuple[str, str]:
    """``MODEL@BASE_URL`` (or just ``MODEL`` for OpenAI itself) -> (model, base_url)."""
    match = re.match(r"^(?P<model>[^@]+?)(?:@(?P<url>https?://\S+))?$", target.strip())
    if not match or not match.group("model"):
        raise SUTConfigError(f"cannot read the SUT spec 'openai:{target}'; write openai:MODEL@BASE_URL, "
                             "e.g. openai:gpt-4o@https://api.openai.com/v1 or openai:moondream@http://localhost:11434/v1")
    return match.group("model"), (match.group("url") or DEFAULT_BASE_URL).rstrip("/")


class OpenAIChatAdapter:
    def __init__(self, target: str, *, timeout_s: float = 60.0, **options: Any):
        where = f"SUT openai:{target}"
        self.model, self.base_url = parse_target(target)
        opts = take_options(options, OPTIONS, where)
        self._key = os.environ.get(str(opts["api_key_env"])) or None
        host = urlparse(self.base_url).hostname or ""
        if self._key is None and host.endswith(_KEYED_HOSTS):
            raise SUTConfigError(f"{where}: no API key; set the environment variable {opts['api_key_env']} "
                                 "(or name another one with --sut-option api_key_env=NAME)")
        if opts["auth"] not in ("bearer", "api-key"):
            raise SUTConfigError(f"{where}: option auth must be 'bearer' or 'api-key', got {opts['auth']!r}")
        if opts["json_mode"] not in ("auto", "on", "off"):
            raise SUTConfigError(f"{where}: option json_mode must be auto, on or off, got {opts['json_mode']!r}")
        self.opts = opts
        self.id = f"openai:{self.model}@{self.base_url}"
        self.fingerprint = fingerprint("openai", self.id, {k: opts[k] for k in _ANSWER_OPTIONS})
        self.model_version = f"model {self.model}"   # what a replay names
        self.redact = Redactor([self._key])
        self._json_ok = opts["json_mode"] != "off"
        self._lock = threading.Lock()
        self.client = http_client(opts, timeout_s, self.redact, where)

    # ------------------------------------------------------------------ request
    @property
    def url(self) -> str:
        version = self.opts["api_version"]
        return f"{self.base_url}/chat/completions" + (f"?api-version={version}" if version else "")

    def _headers(self) -> dict[str, str]:
        if not self._key:
            return {}
        if self.opts["auth"] == "api-key":
            return {"api-key": self._key}
        return {"Authorization": f"Bearer {self._key}"}

    def payload(self, request: SUTRequest, json_mode: bool) -> dict[str, Any]:
        image: dict[str, Any] = {"url": image_data_url(request.image)}
        if self.opts["detail"]:
            image["detail"] = self.opts["detail"]
        body: dict[str, Any] = {"model": self.model, "messages": [{"role": "user", "content": [
            {"type": "text", "text": request.prompt}, {"type": "image_url", "image_url": image}]}]}
        # Sent only when asked for: some models reject any temperature but the default.
        if self.opts["temperature"] is not None:
            body["temperature"] = float(self.opts["temperature"])
        if self.opts["max_tokens"] is not None:
            body["max_tokens"] = int(self.opts["max_tokens"])
        if json_mode:
            body["response_format"] = {"type": "json_object"}
        return body

    # ------------------------------------------------------------------ exchange
    def send(self, request: SUTRequest) -> Exchange:
        json_mode = request.mode == "vqa" and self._json_ok
        try:
            reply = self.client.post_json(self.url, self.payload(request, json_mode), self._headers())
        except TransportError as exc:
            if json_mode and self.opts["json_mode"] == "auto" and _rejects_json_mode(exc):
                with self._lock:
                    self._json_ok = False  # this server has no JSON mode: stop asking for it
                return self.send(request)
            return Exchange(error=str(exc), meta={"status": exc.status, "attempts": exc.attempts})
        return self._read(reply)

    def _read(self, reply) -> Exchange:
        meta = {"status": reply.status, "attempts": reply.attempts}
        try:
            choice = reply.json()["choices"][0]
            message = choice.get("message") or {}
        except (ValueError, KeyError, IndexError, TypeError, AttributeError):
            return Exchange(raw=reply.text, error="unparseable: the server's reply is not a chat completion "
                            f"(no choices[0].message); it begins {reply.text[:120]!r}",
                            latency_s=reply.latency_s, meta=meta)
        meta["finish_reason"] = choice.get("finish_reason")
        content = _text_of(message.get("content"))
        if not content and message.get("refusal"):
            return Exchange(raw=reply.text, error=f"refused: {self.redact(str(message['refusal']))[:200]}",
                            latency_s=reply.latency_s, meta=meta)
        if not content and choice.get("finish_reason") == "content_filter":
            return Exchange(raw=reply.text, error="refused: the provider's content filter withheld the answer",
                            latency_s=reply.latency_s, meta=meta)
        if not content.strip():
            return Exchange(raw=reply.text, error="empty reply from the model (finish_reason "
                            f"{choice.get('finish_reason')!r}; raise max_tokens if it is 'length')",
                            latency_s=reply.latency_s, meta=meta)
        return Exchange(raw=content, content=content, latency_s=reply.latency_s, meta=meta)

    def close(self) -> None:
        self.client.close()


def _text_of(content: Any) -> str:
    """Message content is a string, or (newer servers) a list of typed parts."""
    if isinstance(content, list):
        return "".join(part.get("text", "") for part in content if isinstance(part, dict))
    return content if isinstance(content, str) else ""


def _rejects_json_mode(exc: TransportError) -> bool:
    return exc.status in (400, 422) and bool(re.search(r"response_format|json_object|json mode", str(exc), re.I))


def open_openai(target: str, **kwargs: Any) -> OpenAIChatAdapter:
    return OpenAIChatAdapter(target, **kwargs)

