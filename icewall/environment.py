"""The ICEWALL_* environment variables, checked once before a command runs (icewall.cli), so
a bad value is one clear line and exit code 2, not a traceback deep inside the solver."""

from __future__ import annotations

import os

from icewall.errors import IcewallError

# name -> (accepted values, what it chooses); kept in step with icewall.sparse and
# icewall.materials.concrete_compiled, which read them (tests/reliability checks both ways)
VARIABLES = {
    "ICEWALL_SPARSE_SOLVER": (("auto", "superlu", "umfpack", "pardiso"), "sparse solver"),
    "ICEWALL_SUPERLU_ORDERING": (("NATURAL", "MMD_ATA", "MMD_AT_PLUS_A", "COLAMD"),
                                 "SuperLU column ordering"),
    "ICEWALL_CONCRETE_KERNEL": (("auto", "numpy", "numba"), "concrete update kernel"),
    "ICEWALL_TRACEBACK": (("0", "1"), "1: show the traceback of an internal error"),
}
_UPPER_CASE = {"ICEWALL_SUPERLU_ORDERING"}  # read upper-cased; the others lower-cased


class EnvironmentValueError(IcewallError):
    """An ICEWALL_* environment variable has a value icewall does not know (exit code 2)."""

    exit_code = 2


def check_environment(environ: dict[str, str] | None = None) -> None:
    """Raise EnvironmentValueError for the first ICEWALL_* variable with an unknown value
    (an empty value counts as unset, as where the variables are read)."""
    environ = os.environ if environ is None else environ
    for name, (allowed, what) in VARIABLES.items():
        raw = environ.get(name, "").strip()
        value = raw.upper() if name in _UPPER_CASE else raw.lower()
        if raw and value not in allowed:
            raise EnvironmentValueError(f"environment variable {name}={raw!r}: not a "
                                        f"{what}; expected one of {', '.join(allowed)}")
