"""Client-side limits for remote SUTs: concurrent requests and requests per minute.

Limits hold per process.  With a process pool of N workers, give each worker
1/N of the provider's budget (``rpm``); the retry logic absorbs the rest as 429s.
"""
from __future__ import annotations

import threading
import time
from collections import deque
from contextlib import contextmanager

from ..errors import InputError


class RateLimiter:
    def __init__(self, max_concurrency: int = 4, rpm: float | None = None, clock=time.monotonic, sleep=time.sleep):
        if max_concurrency < 1:
            raise InputError(f"max_concurrency must be at least 1, got {max_concurrency}")
        if rpm is not None and rpm <= 0:
            raise InputError(f"rpm (requests per minute) must be positive, got {rpm}")
        self._slots = threading.BoundedSemaphore(max_concurrency)
        self.rpm = rpm
        self._starts: deque[float] = deque()
        self._lock = threading.Lock()
        self._clock, self._sleep = clock, sleep

    def _wait_for_window(self) -> None:
        """Sliding 60 s window: at most ``rpm`` request starts in any minute."""
        while self.rpm:
            with self._lock:
                now = self._clock()
                while self._starts and now - self._starts[0] >= 60.0:
                    self._starts.popleft()
                if len(self._starts) < self.rpm:
                    self._starts.append(now)
                    return
                wait = 60.0 - (now - self._starts[0])
            self._sleep(max(wait, 0.001))

    @contextmanager
    def slot(self):
        with self._slots:
            self._wait_for_window()
            yield
