"""Progress of a long job: one live line on a terminal, plain log lines otherwise."""
from __future__ import annotations

import sys
import time


class Progress:
    def __init__(self, total: int | None, label: str = "tests", stream=None, log_every_s: float = 10.0,
                 verdicts: bool = True):
        self.total, self.label = total, label
        self.verdicts = verdicts  # show failure and error counts (tests), or just the count (e.g. renders)
        self.stream = stream or sys.stderr
        self.live = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.monotonic()
        self.done = self.failures = self.errors = self.resumed = 0
        self._last_log = float("-inf")  # the first update always shows
        self.log_every_s = log_every_s

    def update(self, failed: bool = False, errored: bool = False, resumed: bool = False) -> None:
        self.done += 1
        self.failures += bool(failed)
        self.errors += bool(errored)
        self.resumed += bool(resumed)
        now = time.monotonic()
        if self.live or now - self._last_log >= self.log_every_s or self.done == self.total:
            self._last_log = now
            self._emit(self.line())

    def line(self) -> str:
        elapsed = time.monotonic() - self.start
        fresh = self.done - self.resumed
        rate = fresh / elapsed if elapsed > 0 and fresh else 0.0
        parts = [f"{self.label} {self.done}" + (f"/{self.total}" if self.total else "")]
        if self.verdicts:
            parts += [f"failures {self.failures}", f"SUT/render errors {self.errors}"]
        parts.append(f"{rate:.2f}/s")
        if self.resumed:
            parts.append(f"resumed {self.resumed}")
        if self.total and rate > 0:
            parts.append(f"ETA {(self.total - self.done) / rate:.0f}s")
        return "  ".join(parts)

    def _emit(self, text: str) -> None:
        if self.live:
            self.stream.write("\r\033[K" + text)
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.live:
            self.stream.write("\n")
            self.stream.flush()


def tracked(items: list, label: str):
    """Yield ``items`` with a progress line (counts, rate, ETA) under ``label``."""
    progress = Progress(len(items), label=label, verdicts=False)
    for item in items:
        yield item
        progress.update()
    progress.close()
