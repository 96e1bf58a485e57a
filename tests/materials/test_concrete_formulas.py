"""The concrete law written once: every point-wise formula of concrete_formulas is what both the
NumPy modules and the numba kernels execute (checked on the sources, so also where numba is
missing), and the kernels' on-disk cache notices a change of the formulas (or of concrete_jit)."""

from __future__ import annotations

import ast
import hashlib
from pathlib import Path

import pytest

from icewall.materials import concrete_formulas

MATERIALS = Path(concrete_formulas.__file__).parent
NUMPY_MODULES = ("concrete", "concrete_law", "mode_rules", "orthotropic", "ultimate_surface",
                 "uniaxial")
KERNELS = "concrete_kernels_compiled"


def _tree(module: str) -> ast.Module:
    return ast.parse((MATERIALS / f"{module}.py").read_text())


def _formulas() -> dict[str, ast.FunctionDef]:
    return {node.name: node for node in _tree("concrete_formulas").body
            if isinstance(node, ast.FunctionDef)}


def _called(tree: ast.AST) -> set[str]:
    """Names of the functions called in `tree` (f(...) and module.f(...))."""
    calls = (node.func for node in ast.walk(tree) if isinstance(node, ast.Call))
    return {f.id if isinstance(f, ast.Name) else f.attr for f in calls
            if isinstance(f, ast.Name | ast.Attribute)}


def _reached(modules: tuple[str, ...]) -> set[str]:
    """The formulas the modules call, directly or through other formulas."""
    formulas = _formulas()
    reached: set[str] = set()
    todo = set().union(*(_called(_tree(m)) for m in modules)) & formulas.keys()
    while todo:
        name = todo.pop()
        reached.add(name)
        todo |= (_called(formulas[name]) & formulas.keys()) - reached
    return reached


def test_every_formula_runs_in_both_kernels():
    formulas = set(_formulas())
    assert not formulas - _reached(NUMPY_MODULES), "formulas the NumPy path does not use"
    assert not formulas - _reached((KERNELS,)), "formulas the numba kernels do not use"


def test_no_module_keeps_its_own_copy_of_a_formula():
    """A function named like a formula elsewhere is a wrapper that calls it (on (n, 4)
    arrays, or after sorting the principal stresses)."""
    formulas = set(_formulas())
    for module in (*NUMPY_MODULES, KERNELS):
        for node in ast.walk(_tree(module)):
            if isinstance(node, ast.FunctionDef) and node.name in formulas:
                assert node.name in _called(node), f"{module}.{node.name}"


def test_formulas_are_plain_arithmetic():
    """No loops, no numba: what NumPy runs batched, numba compiles point by point."""
    tree = _tree("concrete_formulas")
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names}
    imported |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported == {"__future__", "math", "typing", "numpy"}
    for node in _formulas().values():
        assert not any(isinstance(n, ast.For | ast.While | ast.With) for n in ast.walk(node))


def test_kernel_cache_is_keyed_by_the_formulas(monkeypatch):
    pytest.importorskip("numba")
    from numba.core.registry import CPUDispatcher

    from icewall.materials import concrete_jit
    from icewall.materials import concrete_kernels_compiled as kernels

    digest = hashlib.sha256((MATERIALS / "concrete_formulas.py").read_bytes()
                            + (MATERIALS / "concrete_jit.py").read_bytes()).hexdigest()
    assert concrete_jit.SOURCES_DIGEST == digest
    dispatchers = [d for d in vars(kernels).values() if isinstance(d, CPUDispatcher)]
    cached = [d for d in dispatchers if d.targetoptions.get("inline") != "always"]
    assert len(cached) >= 9
    assert all(isinstance(d._cache, concrete_jit.SourceKeyedCache) for d in cached)
    cache, codegen = kernels.trial_pass._cache, kernels.trial_pass.targetctx.codegen()
    key = cache._index_key((), codegen)
    assert key[-1] == digest
    monkeypatch.setattr(concrete_jit, "SOURCES_DIGEST", "changed")
    assert cache._index_key((), codegen) != key
