"""numba for the concrete kernels (imported by concrete_kernels_compiled only).

Registers the formulas of concrete_formulas, so that they compile where a kernel calls them
(register_jitable: the ones of the Newton sweep inlined into it, which lets its loop
vectorise), with their select, clip and remainder as scalar code; and `jit`, numba's cached
njit with NumPy's IEEE semantics, whose cache key also holds SOURCES_DIGEST: numba stamps
the kernel's own file only, and would load a kernel compiled from older formulas (or from an
older version of this file).
"""

from __future__ import annotations

import hashlib
import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

from numba import njit
from numba.core import types
from numba.core.caching import FunctionCache
from numba.extending import intrinsic, overload, register_jitable

from icewall.materials import concrete_formulas as law

SOURCES_DIGEST = hashlib.sha256(b"".join(
    Path(file).read_bytes() for file in (law.__file__, __file__))).hexdigest()
INLINED = ("newton_step", "ray_function", "elliptic_radius_slope", "_elliptic_terms",
           "meridian")


class SourceKeyedCache(FunctionCache):
    """numba's on-disk cache of a kernel, its index key extended by SOURCES_DIGEST."""

    def _index_key(self, sig: Any, codegen: Any) -> tuple:
        return (*super()._index_key(sig, codegen), SOURCES_DIGEST)


def jit(function: Callable) -> Any:
    """A cached kernel with NumPy's IEEE semantics (1/0 = inf, no raise)."""
    dispatcher = njit(error_model="numpy")(function)
    dispatcher._cache = SourceKeyedCache(function)  # what cache=True sets, with our key
    return dispatcher


@intrinsic
def fma(typingctx, a, b, c):
    """a b + c rounded once (the BLAS kernels' vfmadd)."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)
    return types.float64(types.float64, types.float64, types.float64), codegen


@intrinsic
def _select(typingctx, condition, if_true, if_false):
    """LLVM's select: both sides evaluated, as in np.where, and no branch (loops vectorise)."""
    kind = typingctx.unify_types(if_true, if_false)

    def codegen(context, builder, signature, args):
        flag = context.cast(builder, args[0], condition, types.boolean)
        return builder.select(flag, context.cast(builder, args[1], if_true, kind),
                              context.cast(builder, args[2], if_false, kind))
    return kind(condition, if_true, if_false), codegen


@overload(law.select)
def _overload_select(condition, if_true, if_false):
    return lambda condition, if_true, if_false: _select(condition, if_true, if_false)


@overload(law.clip)
def _overload_clip(x, low, high):
    def scalar_clip(x, low, high):  # np.clip's order: max with low, then min with high
        x = _select((x != x) | (x > low), x, low)
        return _select((x != x) | (x < high), x, high)
    return scalar_clip


@overload(law.remainder)
def _overload_remainder(x, y):
    return lambda x, y: x % y  # CPython's float %: fmod, + y where the signs differ


for _formula in vars(law).values():
    if (inspect.isfunction(_formula) and _formula.__module__ == law.__name__
            and _formula not in (law.select, law.clip, law.remainder)):
        register_jitable(inline="always" if _formula.__name__ in INLINED else "never")(_formula)
