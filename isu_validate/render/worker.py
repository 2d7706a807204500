"""The host's handle on one Blender worker subprocess: start, request with a timeout, detect a crash.

The worker speaks JSON lines: requests on its stdin, replies on a dedicated pipe, so that Blender's
console noise (its stdout/stderr) can go to a log file without mixing with the protocol."""
from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path


class WorkerCrashed(RuntimeError):
    """The worker process died (or closed its reply pipe)."""


class WorkerTimeout(RuntimeError):
    """The worker did not answer in time; it has been killed."""


class WorkerFailed(RuntimeError):
    """The worker raised a Python exception while handling a request (it is still alive)."""


class BlenderWorker:
    def __init__(self, log_path: Path):
        self.log_path = Path(log_path)
        self.proc: subprocess.Popen | None = None
        self._fd: int | None = None
        self._buf = b""

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc else None

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def start(self, cabin: dict, timeout_s: float = 180.0) -> dict:
        """Start Blender and build the cabin; returns the worker's hello and init replies merged."""
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        read_fd, write_fd = os.pipe()
        env = dict(os.environ, ISU_RESPONSE_FD=str(write_fd))
        with open(self.log_path, "ab") as log:
            log.write(f"\n===== worker start {time.strftime('%Y-%m-%d %H:%M:%S')} =====\n".encode())
            log.flush()
            # own session: a Ctrl-C in the user's terminal reaches the host, which shuts the worker down
            self.proc = subprocess.Popen([sys.executable, "-m", "isu_validate.render.blender.main"],
                                         stdin=subprocess.PIPE, stdout=log, stderr=subprocess.STDOUT,
                                         pass_fds=(write_fd,), env=env, start_new_session=True)
        os.close(write_fd)
        self._fd, self._buf = read_fd, b""
        hello = self._read(timeout_s)
        init = self.request({"op": "init", "cabin": cabin}, timeout_s)
        return {**hello, **init}

    def request(self, message: dict, timeout_s: float) -> dict:
        if not self.alive:
            raise WorkerCrashed(self._death_note())
        try:
            self.proc.stdin.write((json.dumps(message) + "\n").encode())
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError):
            raise WorkerCrashed(self._death_note()) from None
        reply = self._read(timeout_s)
        if not reply.get("ok"):
            raise WorkerFailed(reply.get("error", "unknown error"))
        return reply

    def _read(self, timeout_s: float) -> dict:
        deadline = time.monotonic() + timeout_s
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                self.kill()
                raise WorkerTimeout(f"Blender worker gave no answer within {timeout_s:.0f} s; killed it "
                                    f"(raise timeout_s for slow presets; log: {self.log_path})")
            ready, _, _ = select.select([self._fd], [], [], min(left, 1.0))
            if ready:
                chunk = os.read(self._fd, 65536)
                if not chunk:
                    raise WorkerCrashed(self._death_note())
                self._buf += chunk
            elif not self.alive:
                raise WorkerCrashed(self._death_note())
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line)

    def _death_note(self) -> str:
        code = self.proc.poll() if self.proc else None
        if code is None and self.proc is not None:
            try:
                code = self.proc.wait(timeout=2)
            except subprocess.TimeoutExpired:
                code = "still running"
        return f"Blender worker (pid {self.pid}) died with exit status {code}; last log lines:\n{self.log_tail()}"

    def log_tail(self, lines: int = 15) -> str:
        try:
            return "\n".join(self.log_path.read_text(errors="replace").splitlines()[-lines:])
        except OSError:
            return "(no log)"

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)   # the worker leads its own process group
            except ProcessLookupError:
                pass
            self.proc.wait()
        self._close_pipes()

    def close(self) -> None:
        """Ask the worker to quit; kill it if it does not."""
        if self.alive:
            try:
                self.request({"op": "quit"}, timeout_s=10)
                self.proc.wait(timeout=10)
            except (WorkerCrashed, WorkerTimeout, WorkerFailed, subprocess.TimeoutExpired):
                pass
        self.kill()

    def _close_pipes(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self.proc is not None and self.proc.stdin and not self.proc.stdin.closed:
            try:
                self.proc.stdin.close()
            except OSError:
                pass
