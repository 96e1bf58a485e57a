"""The few exception types icewall raises; the CLI maps them to exit codes."""

from __future__ import annotations


class IcewallError(Exception):
    """Base class of all icewall errors."""

    exit_code = 1


class DeckError(IcewallError):
    """Invalid input deck: message names file, line and key (exit code 2)."""

    exit_code = 2

    def __init__(self, message: str, file: str | None = None, line: int | None = None,
                 key: str | None = None) -> None:
        self.file, self.line, self.key, self.detail = file, line, key, message
        where = file or "<deck>"
        if line is not None:
            where += f":{line}"
        prefix = f"{where}: " + (f"{key}: " if key else "")
        super().__init__(prefix + message)


class MeshError(IcewallError):
    """Geometry or meshing failed."""


class ResultError(IcewallError):
    """A result file is missing, unreadable or not an icewall result."""

    exit_code = 2


class ConvergenceError(IcewallError):
    """The nonlinear solver stopped; `reason` names why."""

    def __init__(self, message: str, reason: str = "non-convergence") -> None:
        self.reason = reason
        super().__init__(message)


class Interrupted(IcewallError):
    """The run was stopped by a signal (SIGINT, SIGTERM); finished steps are kept."""

    def __init__(self, signal_name: str, exit_code: int) -> None:
        self.exit_code = exit_code
        super().__init__(f"interrupted by {signal_name}")
