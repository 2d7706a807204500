"""``http:URL``: POST the image and questions as JSON to a service; map its JSON reply.

Request body (one JSON object):
``{"mode": "vqa"|"vc", "prompt": TEXT, "questions": [{"key", "question", "options"}],
"image": BASE64, "image_media_type": "image/png"}`` (with ``image=path``: ``"image_path": PATH``
instead of the bytes, for services on the same machine).

Reply mapping, the small configuration (``--sut-option NAME=VALUE``):
  answers_path   dotted path to the answers object in the reply (default "answers"; "" = the whole reply)
  caption_path   dotted path to the caption string (default "caption")
  key_map        their keys to ours, "belt:seat_belt,gender:driver_gender" (default: none)
  image          "base64" (default) or "path"
  api_key_env    if set, the key in that variable is sent as "Authorization: Bearer ..."
  max_concurrency, rpm, max_retries, backoff_s, backoff_max_s, retry_after_max_s   as for openai:
Answers then go through the same tolerant parser as any other SUT's.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ...protocols import SUTRequest
from ..errors import SUTConfigError, TransportError
from ..exchange import Exchange
from ..redact import Redactor
from .common import fingerprint, http_client, image_base64, media_type, take_options

OPTIONS = {"answers_path": "answers", "caption_path": "caption", "key_map": "", "image": "base64",
           "api_key_env": None, "max_concurrency": 4, "rpm": None, "max_retries": 4, "backoff_s": 1.0,
           "backoff_max_s": 30.0, "retry_after_max_s": 120.0}
_MAPPING = ("answers_path", "caption_path", "key_map", "image")


def parse_key_map(text: str | dict, where: str) -> dict[str, str]:
    if isinstance(text, dict):
        return {str(k): str(v) for k, v in text.items()}
    pairs = [p.strip() for p in str(text or "").split(",") if p.strip()]
    out = {}
    for pair in pairs:
        theirs, sep, ours = pair.partition(":")
        if not sep or not theirs.strip() or not ours.strip():
            raise SUTConfigError(f"{where}: key_map entry {pair!r} must read THEIR_KEY:OUR_KEY")
        out[theirs.strip()] = ours.strip()
    return out


def dig(obj: Any, path: str) -> Any:
    """``a.b.0.c`` into nested dicts and lists; KeyError naming the missing step."""
    for step in [s for s in path.split(".") if s]:
        if isinstance(obj, list) and step.isdigit() and int(step) < len(obj):
            obj = obj[int(step)]
        elif isinstance(obj, dict) and step in obj:
            obj = obj[step]
        else:
            raise KeyError(step)
    return obj


class HttpJsonAdapter:
    def __init__(self, target: str, *, timeout_s: float = 60.0, **options: Any):
        where = f"SUT http:{target}"
        if not target.startswith(("http://", "https://")):
            raise SUTConfigError(f"{where}: write http:URL with a full URL, e.g. http:http://localhost:8080/isu")
        opts = take_options(options, OPTIONS, where)
        if opts["image"] not in ("base64", "path"):
            raise SUTConfigError(f"{where}: option image must be 'base64' or 'path', got {opts['image']!r}")
        self.url, self.opts = target, opts
        self.key_map = parse_key_map(opts["key_map"], where)
        self._key = os.environ.get(opts["api_key_env"]) if opts["api_key_env"] else None
        if opts["api_key_env"] and not self._key:
            raise SUTConfigError(f"{where}: the environment variable {opts['api_key_env']} (api_key_env) is not set")
        self.id = f"http:{target.split('?', 1)[0]}"
        self.fingerprint = fingerprint("http", target, {k: opts[k] for k in _MAPPING})
        self.redact = Redactor([self._key])
        self.client = http_client(opts, timeout_s, self.redact, where)

    def body(self, request: SUTRequest) -> dict[str, Any]:
        body: dict[str, Any] = {"mode": request.mode, "prompt": request.prompt}
        if request.mode == "vqa":
            body["questions"] = [q.to_dict() for q in request.questions]
        if self.opts["image"] == "path":
            body["image_path"] = str(Path(request.image).resolve())
        else:
            body["image"], body["image_media_type"] = image_base64(request.image), media_type(request.image)
        return body

    def send(self, request: SUTRequest) -> Exchange:
        headers = {"Authorization": f"Bearer {self._key}"} if self._key else {}
        try:
            reply = self.client.post_json(self.url, self.body(request), headers)
        except TransportError as exc:
            return Exchange(error=str(exc), meta={"status": exc.status, "attempts": exc.attempts})
        meta = {"status": reply.status, "attempts": reply.attempts}
        try:
            content = self._map(reply.json(), request.mode)
        except (ValueError, KeyError) as exc:
            return Exchange(raw=reply.text, error=f"unparseable: {exc}", latency_s=reply.latency_s, meta=meta)
        return Exchange(raw=reply.text, content=content, latency_s=reply.latency_s, meta=meta)

    def _map(self, reply: Any, mode: str) -> Any:
        path = self.opts["caption_path"] if mode == "vc" else self.opts["answers_path"]
        try:
            value = dig(reply, path)
        except KeyError as exc:
            raise KeyError(f"the reply has no {path!r} (missing step {exc.args[0]!r}); set the "
                           f"{'caption' if mode == 'vc' else 'answers'}_path option") from None
        if mode == "vc":
            return {"caption": value} if isinstance(value, str) else value
        if isinstance(value, dict) and self.key_map:
            value = {self.key_map.get(k, k): v for k, v in value.items()}
        return value

    def close(self) -> None:
        self.client.close()


def open_http(target: str, **kwargs: Any) -> HttpJsonAdapter:
    return HttpJsonAdapter(target, **kwargs)
