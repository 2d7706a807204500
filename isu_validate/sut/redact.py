"""Keep API keys out of everything that is stored or shown (archive, logs, errors, reports)."""
from __future__ import annotations

import re
from typing import Iterable

MASK = "[REDACTED]"

# Credentials that have a recognisable shape even when we were not told the value:
# bearer tokens, OpenAI/Anthropic style keys, Google API keys, key=... query parameters.
_PATTERNS = [
    re.compile(r"(?i)(bearer\s+)[A-Za-z0-9._~+/=-]{8,}"),
    re.compile(r"(?i)((?:api[-_]?key|access[-_]?token|x-goog-api-key)[\"']?\s*[=:]\s*[\"']?)[A-Za-z0-9._~+/-]{8,}"),
    re.compile(r"()\bsk-[A-Za-z0-9_-]{8,}"),
    re.compile(r"()\bAIza[0-9A-Za-z_-]{20,}"),
]


class Redactor:
    """Masks the given secret values and anything shaped like a credential."""

    def __init__(self, secrets: Iterable[str | None] = ()):
        # Very short values would mask ordinary words; real keys are long.
        self.secrets = sorted({s for s in secrets if s and len(s) >= 6}, key=len, reverse=True)

    def __call__(self, text: str | None) -> str:
        if not text:
            return text or ""
        for secret in self.secrets:
            text = text.replace(secret, MASK)
        for pattern in _PATTERNS:
            text = pattern.sub(lambda m: m.group(1) + MASK, text)
        return text


def redact(text: str | None, secrets: Iterable[str | None] = ()) -> str:
    return Redactor(secrets)(text)
