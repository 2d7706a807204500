"""Errors of the SUT layer.

A SUT that times out, fails over HTTP or says something unparseable is *recorded*
(``SUTResponse.error``), never raised: such a scene is not a failure-inducing scene.
What is raised is a configuration problem the user must fix before any answer can
come back (bad spec, missing program, rejected API key): repeating it for every
scene of a run would only hide it.
"""
from __future__ import annotations

from ..errors import UserError


class SUTConfigError(UserError, ValueError):
    """The SUT cannot be reached as configured; the message names the problem and the fix."""


class TransportError(RuntimeError):
    """One exchange with the SUT failed (timeout, HTTP error, crash); recorded as a SUT error."""

    def __init__(self, message: str, *, status: int | None = None, attempts: int = 1):
        super().__init__(message)
        self.status = status
        self.attempts = attempts
