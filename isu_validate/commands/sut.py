"""``isu-validate sut check``: ask a SUT once about one image and show what came back.

    isu-validate sut check --sut openai:gpt-4o@https://api.openai.com/v1 cabin.png
    isu-validate sut check --sut 'command:python my_isu.py' cabin.png --mode vc --json
    isu-validate sut check --sut http:http://localhost:8080/isu cabin.png --scene labels/t0001.json

Without ``--scene`` every predicted feature of the space is asked; with it, only the
scene's active ones, and the answer is judged (F_qa or caption metrics).
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..devices import add_device_argument
from ..errors import InputError, InputNotFound
from ..sut.prompt import DEFAULT_PROMPT_STYLE, PROMPT_STYLES

if TYPE_CHECKING:
    from ..space import Question

EPILOG = """adapter options (--sut-option NAME=VALUE):
  openai:   api_key_env (default OPENAI_API_KEY), auth=bearer|api-key, api_version (Azure),
            json_mode=auto|on|off, temperature, max_tokens, detail, max_concurrency, rpm,
            max_retries, backoff_s, backoff_max_s, retry_after_max_s
  http:     answers_path (default answers), caption_path (default caption),
            key_map=THEIRS:OURS,..., image=base64|path, api_key_env, and the limits above
  command:  cwd
exit status: 0 answered, 1 SUT error (timeout, HTTP failure, unparseable), 2 configuration error"""
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def register(sub) -> None:
    parser = sub.add_parser("sut", help="systems under test: check that one answers")
    sut_sub = parser.add_subparsers(dest="sut_command", metavar="ACTION")
    check = sut_sub.add_parser("check", help="ask a SUT once about an image; print answers, problems, latency",
                               epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    check.add_argument("image", type=Path, help="image file (PNG or JPEG)")
    check.add_argument("--sut", required=True,
                       help="reference | openai:MODEL@BASE_URL | command:PROGRAM ARGS... | http:URL")
    check.add_argument("--mode", choices=("vqa", "vc"), default="vqa", help="questions (vqa) or captioning (vc)")
    check.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    check.add_argument("--scene", type=Path, help="scene JSON (or a run's labels/<test>.json): ask its active "
                                                  "features and judge the answer")
    check.add_argument("--space", default="isu-paper", help="scene space name or TOML file (default: %(default)s)")
    check.add_argument("--prompt",
                       help="replace the captioning prompt, or the VQA rules ({questions} places the questions)")
    check.add_argument("--prompt-style", choices=sorted(PROMPT_STYLES), default=DEFAULT_PROMPT_STYLE,
                       help="wording of the VQA prompt: paper (the paper's Figure 2, default) or compact (earlier)")
    check.add_argument("--repeats", type=int, default=1, help="ask K times, majority vote per feature")
    check.add_argument("--timeout", type=float, default=60.0, help="seconds per request (default: %(default)s)")
    add_device_argument(check)   # the embedded reference ISU's backbone
    check.add_argument("--sut-option", action="append", default=[], metavar="NAME=VALUE",
                       help="adapter option, e.g. api_key_env=MY_KEY, rpm=30, json_mode=off (repeatable)")
    check.add_argument("--cache-dir", type=Path, help="reuse/record replies here (default: no cache)")
    check.set_defaults(func=check_command)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


def parse_options(pairs: list[str]) -> dict[str, str]:
    options = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--sut-option {pair!r} must read NAME=VALUE")
        options[name.strip()] = value
    return options


def all_questions(space) -> tuple[Question, ...]:
    """Every predicted feature, for a check without a scene (truth unknown)."""
    from ..space import Question

    return tuple(Question(f.name, f.question, f.options, f.weight, "") for f in space.predicted)


def _check_image(path: Path) -> None:
    if path.is_dir():
        from ..image_files import IMAGE_SUFFIXES

        example = next((p for p in sorted(path.iterdir()) if p.suffix.lower() in IMAGE_SUFFIXES), None)
        hint = f", e.g. {example}" if example else ""
        raise InputError(f"{path} is a folder; sut check asks about one image: give an image file{hint}")
    if not path.is_file():
        raise InputNotFound(f"image {path} does not exist")


def check_command(args) -> int:
    from ..evaluate import make_judge
    from ..protocols import SUTRequest
    from ..space import load_space, read_scene_file
    from ..sut import build_request, open_sut
    from ..sut.prompt import vqa_prompt

    _check_image(args.image)
    space = load_space(args.space)
    scene = space.check(read_scene_file(args.scene)) if args.scene else None
    if scene is not None:
        request = build_request(space, scene, args.image, args.mode, args.prompt, args.prompt_style)
    elif args.mode == "vqa":
        questions = all_questions(space)
        request = SUTRequest("vqa", args.image, vqa_prompt(space, questions, args.prompt, args.prompt_style), questions)
    else:
        request = build_request(space, {}, args.image, "vc", args.prompt)
    sut = open_sut(args.sut, space=space, repeats=args.repeats, cache_dir=args.cache_dir, timeout_s=args.timeout,
                   device=args.device, **parse_options(args.sut_option))
    try:
        response = sut.query(request)
    finally:
        sut.close()
    result: dict[str, Any] = {"sut": sut.id, "mode": args.mode}
    result["caption" if args.mode == "vc" else "answers"] = response.caption if args.mode == "vc" else response.answers
    result.update(problems=response.problems, latency_s=round(response.latency_s, 3), error=response.error,
                  outcome=response.extra.get("outcome"))
    for key in ("status", "notes", "consistency", "ties"):
        if key in response.extra:
            result[key] = response.extra[key]
    if scene is not None:
        verdict = make_judge(args.mode, space).judge(scene, request, response)
        result["verdict"] = {"fitness": verdict.fitness, "primary": verdict.primary, "failed": verdict.failed,
                             "details": verdict.details}
    if args.json:
        print(json.dumps(result, indent=2, ensure_ascii=False, default=str))
    else:
        print_text(result, response.raw)
    return 1 if response.error else 0


def shown(text: Any) -> str:
    """SUT text is data: control characters (terminal escapes) are shown escaped, never executed."""
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", str(text))


def print_text(result: dict[str, Any], raw: str) -> None:
    out = sys.stdout
    out.write(f"SUT {shown(result['sut'])}  mode {result['mode']}  latency {result['latency_s']:.3f} s  "
              f"outcome {result.get('outcome')}\n")
    if result.get("error"):
        out.write(f"SUT error: {shown(result['error'])}\n")
    if result["mode"] == "vc" and result.get("caption") is not None:
        out.write(f"caption: {shown(result['caption'])}\n")
    if result["mode"] == "vqa" and result.get("status"):
        out.write("answers:\n")
        for key, status in result["status"].items():
            answer = (result.get("answers") or {}).get(key)
            out.write(f"  {key:<24} {answer if answer is not None else '(' + status + ')'}\n")
    for title, items in (("problems", result.get("problems")), ("notes", result.get("notes"))):
        if items:
            out.write(f"{title}:\n" + "".join(f"  - {shown(p)}\n" for p in items))
    if "verdict" in result:
        verdict = result["verdict"]
        scores = ", ".join(f"{k} {v:.3f}" for k, v in verdict["fitness"].items())
        out.write(f"verdict: {scores or 'no fitness (SUT error)'}  failed={verdict['failed']}\n")
        if "reference_caption" in verdict["details"]:
            out.write(f"reference caption: {verdict['details']['reference_caption']}\n")
    if result.get("error") and raw:
        out.write(f"raw reply (first 300 characters): {shown(raw[:300])}\n")
