"""``command:PROGRAM ARGS...``: the command protocol of ARCHITECTURE.md.

The program receives one JSON object on stdin,
``{"mode": "vqa", "image": PATH, "prompt": TEXT, "questions": [{"key", "question", "options"}]}``
or ``{"mode": "vc", "image": PATH, "prompt": TEXT}``, and prints ``{"answers": {K: OPTION}}``
or ``{"caption": TEXT}`` on stdout.  A non-zero exit, a timeout or unparseable output is
a SUT error.  One process per request: the program may keep its own state elsewhere.

Options: ``cwd`` (working directory for the program).
"""
from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import time
from pathlib import Path
from typing import Any

from ...protocols import SUTRequest
from ..errors import SUTConfigError
from ..exchange import Exchange
from ..redact import Redactor
from .common import fingerprint, take_options

OPTIONS = {"cwd": None}
_STDERR_SHOWN = 400


class CommandAdapter:
    def __init__(self, target: str, *, timeout_s: float = 60.0, **options: Any):
        where = f"SUT command:{target}"
        try:
            self.argv = shlex.split(target)
        except ValueError as exc:
            raise SUTConfigError(f"{where}: cannot split the command line ({exc}); check its quotes") from None
        if not self.argv:
            raise SUTConfigError("SUT spec 'command:' names no program; write command:PROGRAM ARGS...")
        opts = take_options(options, OPTIONS, where)
        self.cwd = opts["cwd"]
        program = self.argv[0]
        if shutil.which(program) is None and not Path(program).is_file():
            raise SUTConfigError(f"{where}: program {program!r} not found (not on PATH and not a file)")
        self.timeout_s = timeout_s
        self.id = f"command:{shlex.join(self.argv)}"
        self.fingerprint = fingerprint("command", self.id, {})
        # The program's environment may hold keys; anything it echoes from there is masked.
        self.redact = Redactor(v for k, v in os.environ.items() if any(s in k.upper() for s in ("KEY", "TOKEN", "SECRET")))

    @staticmethod
    def message(request: SUTRequest) -> dict[str, Any]:
        msg: dict[str, Any] = {"mode": request.mode, "image": str(Path(request.image).resolve()), "prompt": request.prompt}
        if request.mode == "vqa":
            msg["questions"] = [q.to_dict() for q in request.questions]
        return msg

    def send(self, request: SUTRequest) -> Exchange:
        start = time.perf_counter()
        try:
            proc = subprocess.run(self.argv, input=json.dumps(self.message(request)), capture_output=True,
                                  text=True, timeout=self.timeout_s, cwd=self.cwd)
        except subprocess.TimeoutExpired:
            return Exchange(error=f"timed out after {self.timeout_s:g} s: {self.id}",
                            latency_s=time.perf_counter() - start)
        except OSError as exc:
            return Exchange(error=f"cannot start {self.id}: {exc}", latency_s=time.perf_counter() - start)
        latency = time.perf_counter() - start
        stdout = self.redact(proc.stdout)
        if proc.returncode != 0:
            tail = self.redact(proc.stderr.strip())[-_STDERR_SHOWN:]
            return Exchange(raw=stdout, error=f"exited with status {proc.returncode}: {json.dumps(tail)}",
                            latency_s=latency, meta={"returncode": proc.returncode})
        try:
            content: Any = json.loads(stdout)
        except ValueError:
            content = stdout  # the tolerant parser decides whether anything usable is in there
        return Exchange(raw=stdout, content=content, latency_s=latency, meta={"returncode": 0})

    def close(self) -> None:
        pass


def open_command(target: str, **kwargs: Any) -> CommandAdapter:
    return CommandAdapter(target, **kwargs)
