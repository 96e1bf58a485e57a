"""The size-based choice of ICEWALL_SPARSE_SOLVER=auto (icewall.sparse.choose_for):
installed backends only, fallback to SuperLU, and every backend and SuperLU ordering it can
pick solving an unsymmetric augmented-like system (zero diagonal block)."""

import numpy as np
import pytest
import scipy.sparse as sp

import icewall.sparse as sparse

SIZES = (10, sparse.AUTO_ORDERING_ROWS, sparse.AUTO_LARGE_ROWS - 1, sparse.AUTO_LARGE_ROWS,
         10**6)


def _augmented_like(seed: int = 0, n: int = 40, m: int = 6) -> sp.csc_matrix:
    """[[K, C^T], [C, 0]]: K unsymmetric, m constraint rows, a zero m x m diagonal block."""
    rng = np.random.default_rng(seed)
    K = sp.random(n, n, density=0.1, random_state=rng) + sp.eye(n) * 4.0
    rows = np.repeat(np.arange(m), 2)
    cols = rng.choice(n, size=2 * m, replace=False)
    C = sp.csr_matrix((np.tile([1.0, -1.0], m), (rows, cols)), shape=(m, n))
    return sp.bmat([[K, C.T], [C, None]], format="csc")


def _relative_residual(A: sp.spmatrix, b: np.ndarray, x: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(A @ x - b, axis=0) / np.linalg.norm(b, axis=0)))


@pytest.fixture
def no_ordering_variable(monkeypatch):
    monkeypatch.delenv(sparse.ORDERING_VARIABLE, raising=False)


@pytest.mark.parametrize("n_rows", SIZES)
def test_choice_is_an_installed_backend(n_rows, no_ordering_variable):
    choice = sparse.choose_for(n_rows)
    assert choice.backend in sparse.available_backends()
    assert (choice.ordering is None) == (choice.backend != "superlu")
    assert sparse.choose_backend("auto", n_rows) == choice.backend


@pytest.mark.parametrize("n_rows", SIZES)
def test_choice_falls_back_to_superlu_without_optional_backends(n_rows, monkeypatch,
                                                                no_ordering_variable):
    monkeypatch.setattr(sparse, "installed", lambda backend: backend == "superlu")
    ordering = "COLAMD" if n_rows < sparse.AUTO_ORDERING_ROWS else "MMD_ATA"
    assert sparse.choose_for(n_rows) == sparse.Choice("superlu", ordering)
    monkeypatch.setenv(sparse.ENVIRONMENT_VARIABLE, "auto")
    A = _augmented_like()
    lu = sparse.factorize(A)  # no warning: auto never asks for a missing backend
    assert lu.backend == "superlu"


def test_choice_by_size_when_every_backend_is_installed(monkeypatch, no_ordering_variable):
    monkeypatch.setattr(sparse, "installed", lambda backend: True)
    assert sparse.choose_for(sparse.AUTO_LARGE_ROWS - 1).backend == "superlu"
    assert sparse.choose_for(sparse.AUTO_LARGE_ROWS).backend == "pardiso"
    monkeypatch.setattr(sparse, "installed", lambda backend: backend != "pardiso")
    assert sparse.choose_for(sparse.AUTO_LARGE_ROWS).backend == "umfpack"


def test_explicit_superlu_ordering_wins_over_auto(monkeypatch):
    monkeypatch.setenv(sparse.ORDERING_VARIABLE, "MMD_ATA")
    assert sparse.choose_for(10) == sparse.Choice("superlu", None)  # superlu_options()


def test_default_backend_is_unchanged(monkeypatch, no_ordering_variable):
    monkeypatch.delenv(sparse.ENVIRONMENT_VARIABLE, raising=False)
    lu = sparse.factorize(_augmented_like())
    assert lu.backend == "superlu"
    assert sparse.superlu_options()["permc_spec"] == "MMD_AT_PLUS_A"


def test_broken_umfpack_build_counts_as_absent(monkeypatch):
    class Broken:
        def UmfpackContext(self, family):  # noqa: N802 (scikit-umfpack's name)
            raise AttributeError("'Struct' object has no attribute 'defaults'")

    monkeypatch.setattr(sparse.importlib, "import_module", lambda name: Broken())
    sparse.installed.cache_clear()
    try:
        assert not sparse.installed("umfpack")
        assert sparse.installed("superlu")
    finally:
        monkeypatch.undo()
        sparse.installed.cache_clear()


@pytest.mark.parametrize("ordering", ("MMD_AT_PLUS_A", "COLAMD", "MMD_ATA", "NATURAL"))
def test_superlu_orderings_solve_an_augmented_like_system(ordering):
    A = _augmented_like(seed=2)
    b = np.random.default_rng(3).random((A.shape[0], 2))
    lu = sparse.SuperLUFactor(A, None, 1e-12, ordering)
    assert lu.lu.perm_c.size == A.shape[0]
    assert _relative_residual(A, b, lu.solve(b)) < 1e-10


@pytest.mark.parametrize("backend", ("auto", *sparse.BACKENDS))
@pytest.mark.parametrize("large", (False, True))
def test_every_choice_solves_an_augmented_like_system(backend, large, monkeypatch,
                                                     no_ordering_variable):
    if backend != "auto" and backend not in sparse.available_backends():
        pytest.skip(f"{backend} not installed")
    if large:  # this small matrix counts as large: auto picks an optional backend if any
        monkeypatch.setattr(sparse, "AUTO_LARGE_ROWS", 10)
    A = _augmented_like(seed=1)
    assert A[-6:, -6:].nnz == 0
    b = np.random.default_rng(4).random((A.shape[0], 2))
    lu = sparse.factorize(A, backend)
    if backend == "auto":
        assert lu.backend == sparse.choose_for(A.shape[0]).backend
    x = lu.solve(b)
    assert _relative_residual(A, b, x) < 1e-10
    assert lu.accurate(b, x)
