"""``command:PROGRAM ARGS...``: the command protocol of docs/ARCHITECTURE.md.

The program receives one JSON object on stdin,
``{"mode": "vqa", "image": PATH, "prompt": TEXT, "questions": [{"key", "question", "options"}]}``
or ``{"mode": "vc", "image": PATH, "prompt": TEXT}``, and prints ``{"answers": {K: OPTION}}``
or ``{"caption": TEXT}`` on stdout.  A non-zero exit, a timeout or unparseable output is
a SUT error.  One process per request: the program may keep its own state elsewhere.
Each request runs in its own process group (session), so a timeout kills the program
and everything it started (a shell script's children would otherwise live on).

Options: ``cwd`` (working directory for the program).
"""
from __future__ import annotations

import json
import os
import shlex
import shutil
import signal
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
        self.redact = Redactor(v for k, v in os.environ.items()
                               if any(s in k.upper() for s in ("KEY", "TOKEN", "SECRET")))

    @staticmethod
    def message(request: SUTRequest) -> dict[str, Any]:
        msg: dict[str, Any] = {"mode": request.mode, "image": str(Path(request.image).resolve()),
                               "prompt": request.prompt}
        if request.mode == "vqa":
            msg["questions"] = [q.to_dict() for q in request.questions]
        return msg

    def send(self, request: SUTRequest) -> Exchange:
        start = time.perf_counter()
        try:
            returncode, stdout, stderr = self._run(json.dumps(self.message(request)))
        except subprocess.TimeoutExpired:
            return Exchange(error=f"timed out after {self.timeout_s:g} s: {self.id}",
                            latency_s=time.perf_counter() - start)
        except OSError as exc:
            return Exchange(error=f"cannot start {self.id}: {exc}", latency_s=time.perf_counter() - start)
        latency = time.perf_counter() - start
        stdout = self.redact(stdout)
        if returncode != 0:
            tail = self.redact(stderr.strip())[-_STDERR_SHOWN:]
            return Exchange(raw=stdout, error=f"exited with status {returncode}: {json.dumps(tail)}",
                            latency_s=latency, meta={"returncode": returncode})
        try:
            content: Any = json.loads(stdout)
        except ValueError:
            content = stdout  # the tolerant parser decides whether anything usable is in there
        return Exchange(raw=stdout, content=content, latency_s=latency, meta={"returncode": 0})

    def _run(self, message: str) -> tuple[int, str, str]:
        """The program's exit status, stdout and stderr.  On a timeout (TimeoutExpired) or any other
        way out of here (Ctrl-C) the program's whole process group is killed first."""
        proc = subprocess.Popen(self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, cwd=self.cwd, start_new_session=True)
        try:
            stdout, stderr = proc.communicate(message, timeout=self.timeout_s)
        except BaseException:
            _kill_group(proc)
            raise
        return proc.returncode, stdout, stderr

    def close(self) -> None:
        pass


def _kill_group(proc: subprocess.Popen) -> None:
    """Kill the program and every process of its group, reap it, and drop the pipes (without
    reading them: a process that left the group could hold them open for ever)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass  # the group is gone already
    proc.wait()
    for stream in (proc.stdin, proc.stdout, proc.stderr):
        if stream:
            stream.close()


def open_command(target: str, **kwargs: Any) -> CommandAdapter:
    return CommandAdapter(target, **kwargs)
