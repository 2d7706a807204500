"""Reading real VLM output: tolerant, but honest.

Models wrap JSON in code fences, add prose, use single quotes or bare words,
change case, answer "Yes"/true for "YES", leave keys out, invent options or
refuse.  We map only variants that cannot mean anything else:

- keys: exact, case/punctuation-insensitive ("Seat Belt" -> seat_belt), or the question's own text;
- values: the option in any case with spaces/hyphens for underscores ("front-facing" -> FRONT_FACING);
  true/"true"/"y" -> YES and false/"false"/"n" -> NO where those are options; null, "N/A" -> NONE
  where NONE is an option; a leading option followed by an explanation ("Yes, she is") when no other
  option occurs in the text.

Everything else is classified, per question: ``answered``, ``missing`` (no key) or ``invalid``
(an answer that is not one of the options, ambiguous, or conflicting).  The whole response is
``answered`` (every question), ``partial`` (some), or a SUT error (no JSON object, or none of
the question keys): an unparseable reply is the SUT's error, not a failure of the scene.
"""
from __future__ import annotations

import ast
import json
import re
from dataclasses import dataclass, field
from typing import Any, Sequence

from ..space import Question

ANSWERED, MISSING, INVALID = "answered", "missing", "invalid"
OUTCOME_ANSWERED, OUTCOME_PARTIAL, OUTCOME_ERROR = "answered", "partial", "error"

_FENCE = re.compile(r"```[ \t]*[A-Za-z0-9_+-]*[ \t]*\n?(.*?)(?:```|\Z)", re.S)
_WRAPPERS = ("answers", "answer", "result", "results", "response", "output", "data", "prediction", "predictions")
_TRUE_WORDS, _FALSE_WORDS = {"TRUE", "Y"}, {"FALSE", "N"}
_NONE_WORDS = {"N/A", "NA", "NULL", "NOT_APPLICABLE"}
_SHOWN = 160  # characters of a reply quoted in an error message


@dataclass
class ParsedAnswers:
    answers: dict[str, str] = field(default_factory=dict)   # valid options only
    status: dict[str, str] = field(default_factory=dict)    # key -> answered | missing | invalid
    problems: list[str] = field(default_factory=list)       # per-feature, human readable
    notes: list[str] = field(default_factory=list)          # variants we mapped (for audit)
    ignored_keys: list[str] = field(default_factory=list)   # keys not asked (e.g. inactive features)
    outcome: str = OUTCOME_ERROR
    error: str | None = None


@dataclass
class ParsedCaption:
    caption: str | None = None
    problems: list[str] = field(default_factory=list)
    error: str | None = None


# ---------------------------------------------------------------- finding the JSON object
def _balanced_spans(text: str) -> list[str]:
    """Top-level ``{...}`` spans, skipping braces inside quoted strings."""
    spans, depth, start, quote, escaped = [], 0, -1, "", False
    for i, ch in enumerate(text):
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == quote:
                quote = ""
            continue
        if ch in "\"'" and depth > 0:
            # An apostrophe inside prose ("driver's") must not open a string.
            if ch == "'" and i > 0 and text[i - 1].isalnum():
                continue
            quote = ch
        elif ch == "{":
            if depth == 0:
                start = i
            depth += 1
        elif ch == "}" and depth > 0:
            depth -= 1
            if depth == 0:
                spans.append(text[start:i + 1])
    return spans


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out and out[key] != value:
            out.setdefault("__conflicts__", []).append(key)
        out[key] = value
    return out


_BARE_KEY = re.compile(r"([{,]\s*)([A-Za-z_][\w \-]*?)\s*:")
_BARE_VALUE = re.compile(r"(:\s*)([A-Za-z_][\w\-/ ]*?)(\s*[,}])")
_SINGLE_QUOTED = re.compile(r"'([^'\\]*)'")
_TRAILING_COMMA = re.compile(r",\s*([}\]])")


def _decode(span: str) -> dict | None:
    """JSON, then a Python literal (single quotes, True/None), then bare words / trailing commas."""
    attempts = [span]
    relaxed = _TRAILING_COMMA.sub(r"\1", _SINGLE_QUOTED.sub(r'"\1"', span))
    relaxed = _BARE_VALUE.sub(lambda m: m.group(1) + json.dumps(m.group(2).strip()) + m.group(3)
                              if m.group(2).strip() not in ("true", "false", "null") else m.group(0), relaxed)
    attempts.append(_BARE_KEY.sub(lambda m: m.group(1) + json.dumps(m.group(2).strip()) + ":", relaxed))
    for i, text in enumerate(attempts):
        try:
            value = json.loads(text, object_pairs_hook=_no_duplicates)
        except ValueError:
            if i == 0:
                try:
                    value = ast.literal_eval(text)
                except (ValueError, SyntaxError, MemoryError, RecursionError):
                    continue
            else:
                continue
        if isinstance(value, dict):
            return value
    return None


def candidate_objects(text: str) -> list[dict]:
    """Every JSON-like object in a reply: inside code fences first, then in the prose around them."""
    fenced = [m.group(1) for m in _FENCE.finditer(text)]
    outside = _FENCE.sub(" ", text)
    found = []
    for chunk in fenced + [outside]:
        for span in _balanced_spans(chunk):
            obj = _decode(span)
            if obj is not None:
                found.append(obj)
    return found


def _key_lines(text: str, questions: Sequence[Question]) -> dict:
    """``key: value`` lines (no JSON at all) whose key is exactly a question key."""
    keys = {q.key.lower(): q.key for q in questions}
    out = {}
    for line in text.splitlines():
        m = re.match(r"^\s*[-*]?\s*[\"']?([A-Za-z_]+)[\"']?\s*[:=]\s*(.+?)\s*,?\s*$", line)
        if m and m.group(1).lower() in keys:
            out[keys[m.group(1).lower()]] = m.group(2).strip().strip("\"'")
    return out


# ---------------------------------------------------------------- keys
def _norm_key(key: Any) -> str:
    return re.sub(r"[^a-z0-9]", "", str(key).lower())


def _key_index(questions: Sequence[Question]) -> dict[str, str]:
    index = {}
    for q in questions:
        index[_norm_key(q.question)] = q.key
    for q in questions:  # keys win over question texts
        index[_norm_key(q.key)] = q.key
    return index


def _unwrap(obj: Any, index: dict[str, str]) -> Any:
    """``{"answers": {...}}`` or ``[{"key": k, "answer": v}]`` -> the flat mapping."""
    for _ in range(3):
        if isinstance(obj, list) and all(isinstance(x, dict) and "key" in x for x in obj):
            obj = {x["key"]: x.get("answer", x.get("value")) for x in obj}
        if not isinstance(obj, dict) or any(_norm_key(k) in index for k in obj):
            return obj
        inner = [v for k, v in obj.items() if str(k).lower() in _WRAPPERS and isinstance(v, (dict, list))]
        if len(inner) != 1:
            return obj
        obj = inner[0]
    return obj


def _known_keys(obj: Any, index: dict[str, str]) -> int:
    return sum(_norm_key(k) in index for k in obj) if isinstance(obj, dict) else 0


# ---------------------------------------------------------------- values
def _words(text: str) -> list[str]:
    return re.findall(r"[A-Z0-9/]+", text.upper())


def normalise_answer(value: Any, options: Sequence[str]) -> tuple[str | None, str | None]:
    """(option, note) for an unambiguous answer; (None, reason) otherwise."""
    if isinstance(value, dict):
        inner = [value[k] for k in ("answer", "value", "option") if k in value]
        return normalise_answer(inner[0], options) if inner else (None, f"an object {json.dumps(value)[:60]}")
    if isinstance(value, list):
        return normalise_answer(value[0], options) if len(value) == 1 else (None, f"{len(value)} answers")
    if isinstance(value, bool):
        word = "YES" if value else "NO"
        return (word, f"{value!r} read as {word}") if word in options else (None, f"{value!r} (not an option)")
    if value is None:
        return ("NONE", "null read as NONE") if "NONE" in options else (None, "null")
    if not isinstance(value, str):
        return None, f"{value!r} (not an option)"
    words = _words(value)
    if not words:
        return None, "an empty answer"
    mapped = _map_words(words, options)
    if mapped:
        return mapped, None if "_".join(words) == mapped else f"{value!r} read as {mapped}"
    for option in sorted(options, key=len, reverse=True):  # "Yes, the driver is" -> YES
        opt_words = _words(option.replace("_", " "))
        if words[:len(opt_words)] == opt_words or _map_words(words[:1], options) == option:
            rest = words[len(opt_words) if words[:len(opt_words)] == opt_words else 1:]
            others = [o for o in options if o != option and _contains(rest, _words(o.replace("_", " ")))]
            if others:
                return None, f"{value!r} is ambiguous ({option} and {', '.join(others)})"
            return option, f"{value!r} read as {option}"
    return None, f"{value!r} is not one of the options {', '.join(options)}"


def _map_words(words: list[str], options: Sequence[str]) -> str | None:
    joined = "_".join(words)
    if joined in options:
        return joined
    if joined in _TRUE_WORDS and "YES" in options:
        return "YES"
    if joined in _FALSE_WORDS and "NO" in options:
        return "NO"
    if (joined in _NONE_WORDS or "/".join(words) in _NONE_WORDS) and "NONE" in options:
        return "NONE"
    return None


def _contains(words: list[str], sub: list[str]) -> bool:
    return any(words[i:i + len(sub)] == sub for i in range(len(words) - len(sub) + 1))


# ---------------------------------------------------------------- VQA
def parse_vqa(content: Any, questions: Sequence[Question]) -> ParsedAnswers:
    """Parse a reply (text, or an already decoded JSON object) against the asked questions."""
    index = _key_index(questions)
    result = ParsedAnswers()
    obj = _choose_object(content, questions, index, result)
    if obj is None:
        return result
    by_key: dict[str, list[Any]] = {}
    for raw_key, value in obj.items():
        if raw_key == "__conflicts__":
            continue
        key = index.get(_norm_key(raw_key))
        if key is None:
            result.ignored_keys.append(str(raw_key))
        else:
            by_key.setdefault(key, []).append(value)
    conflicts = {index.get(_norm_key(k)) for k in obj.get("__conflicts__", [])}
    for q in questions:
        _classify(q, by_key.get(q.key, []), q.key in conflicts, result)
    answered = sum(s == ANSWERED for s in result.status.values())
    result.outcome = OUTCOME_ANSWERED if answered == len(questions) else OUTCOME_PARTIAL
    if result.ignored_keys:
        result.notes.append(f"ignored keys not asked: {', '.join(result.ignored_keys[:10])}")
    return result


def _choose_object(content: Any, questions, index, result: ParsedAnswers) -> dict | None:
    """The object with the most question keys (the last one on a tie: models revise drafts)."""
    if isinstance(content, (dict, list)):
        candidates = [content]
    else:
        text = str(content or "")
        candidates = candidate_objects(text)
        lines = _key_lines(text, questions) if not candidates else {}
        if lines:
            candidates = [lines]
            result.notes.append("read from key: value lines, not JSON")
    unwrapped = [_unwrap(c, index) for c in candidates]
    scored = [(c, _known_keys(c, index)) for c in unwrapped]
    best = max((s for _, s in scored), default=0)
    if best == 0:
        result.error = _unparseable(content, candidates)
        return None
    if sum(s > 0 for _, s in scored) > 1:
        result.notes.append(f"{len(scored)} JSON objects in the reply; used the one answering most questions")
    return [c for c, s in scored if s == best][-1]


def _unparseable(content: Any, candidates: list) -> str:
    if not candidates:
        shown = json.dumps(str(content or "").strip()[:_SHOWN], ensure_ascii=False)
        return f"unparseable: no JSON object in the reply (it begins {shown})"
    keys = sorted({str(k) for c in candidates if isinstance(c, dict) for k in c})[:10]
    return f"unparseable: the reply's JSON names none of the question keys (it has {', '.join(keys) or 'no keys'})"


def _classify(q: Question, values: list[Any], conflicting: bool, result: ParsedAnswers) -> None:
    if not values:
        result.status[q.key] = MISSING
        result.problems.append(f"{q.key}: missing (no answer for this question)")
        return
    mapped = [normalise_answer(v, q.options) for v in values]
    chosen = {m[0] for m in mapped}
    if conflicting or len(chosen) > 1 or None in chosen:
        reason = "conflicting answers" if (conflicting or len(chosen) > 1) and None not in chosen else \
            next(note for option, note in mapped if option is None)
        result.status[q.key] = INVALID
        result.problems.append(f"{q.key}: invalid answer: {reason}")
        return
    result.status[q.key] = ANSWERED
    result.answers[q.key] = chosen.pop()
    result.notes.extend(f"{q.key}: {note}" for _, note in mapped if note)


# ---------------------------------------------------------------- captions
def parse_caption(content: Any) -> ParsedCaption:
    """A caption from free text, or from a JSON ``{"caption": ...}`` reply."""
    if isinstance(content, dict):
        value = content.get("caption")
        if not isinstance(value, str):
            keys = ", ".join(map(str, list(content)[:10])) or "no keys"
            return ParsedCaption(error=f"unparseable: the reply has no \"caption\" string (it has {keys})")
        text = value
    else:
        text = str(content or "")
        objects = candidate_objects(text) if text.lstrip().startswith(("{", "```")) else []
        captions = [o["caption"] for o in objects if isinstance(o.get("caption"), str)]
        if captions:
            text = captions[-1]
        elif text.strip().startswith("```"):
            text = "\n".join(m.group(1) for m in _FENCE.finditer(text))
    text = text.strip()
    if not text:
        return ParsedCaption(error="empty caption: the SUT returned no text")
    return ParsedCaption(caption=text)
