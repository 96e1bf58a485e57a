"""The sparse direct solver backends (icewall.sparse): selection and clean fallback,
solutions against dense LAPACK, singular matrices; the one-pass augmented matrix against its
block definition (eq. 3.35) built densely."""

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

import icewall.sparse as sparse
from icewall.errors import ConvergenceError
from icewall.interface.augmented import augmented_matrix, factorize
from icewall.interface.gap import FIXED, FREE, SLIP, GapState
from icewall.solve.constraints import Factorization, restricted_matrix


def _saddle_system(seed: int = 0) -> sp.csc_matrix:
    """An unsymmetric 'stiffness' plus two constraint rows with a zero diagonal block."""
    rng = np.random.default_rng(seed)
    n = 30
    K = sp.random(n, n, density=0.15, random_state=rng) + sp.eye(n) * 5.0
    C = sp.csr_matrix(([1.0, -1.0, 1.0, -1.0], ([0, 0, 1, 1], [3, 4, 10, 11])), shape=(2, n))
    return sp.bmat([[K, C.T], [C, None]], format="csc")


@pytest.mark.parametrize("backend", sparse.BACKENDS)
def test_every_installed_backend_matches_dense_lapack(backend):
    if backend not in sparse.available_backends():
        pytest.skip(f"{backend} not installed")
    A = _saddle_system()
    b = np.random.default_rng(1).random((A.shape[0], 2))
    lu = sparse.factorize(A, backend)
    x = lu.solve(b)
    assert lu.backend == backend
    np.testing.assert_allclose(x, np.linalg.solve(A.toarray(), b), rtol=1e-9, atol=1e-12)
    assert lu.accurate(b, x) and not lu.accurate(b, x + 1.0)  # the residual check
    other = sparse.factorize(2.0 * A, backend)  # a newer factorisation (shared handles)
    np.testing.assert_allclose(other.solve(b), 0.5 * x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(lu.solve(b), x, rtol=1e-9, atol=1e-12)  # the older still holds


def test_absent_optional_backend_falls_back_to_superlu(monkeypatch):
    monkeypatch.setattr(sparse, "installed", lambda backend: backend == "superlu")
    with pytest.warns(RuntimeWarning, match="not installed"):
        assert sparse.choose_backend("pardiso") == "superlu"
    monkeypatch.setenv(sparse.ENVIRONMENT_VARIABLE, "umfpack")
    A = _saddle_system()
    with pytest.warns(RuntimeWarning, match="not installed"):
        lu = sparse.factorize(A)
    assert lu.backend == "superlu"
    b = np.ones(A.shape[0])
    np.testing.assert_allclose(A @ lu.solve(b), b, atol=1e-10)
    assert sparse.choose_backend("auto") == "superlu"


def test_backend_choice_defaults_to_superlu_and_rejects_unknown_names(monkeypatch):
    monkeypatch.delenv(sparse.ENVIRONMENT_VARIABLE, raising=False)
    assert sparse.choose_backend() == "superlu"
    assert sparse.choose_backend("auto") == next(
        b for b in ("umfpack", "pardiso", "superlu") if b in sparse.available_backends())
    with pytest.raises(ValueError, match="unknown sparse solver"):
        sparse.choose_backend("mumps")


def test_superlu_ordering_comes_from_the_environment(monkeypatch):
    monkeypatch.delenv(sparse.ORDERING_VARIABLE, raising=False)
    assert sparse.superlu_options()["permc_spec"] == "MMD_AT_PLUS_A"
    monkeypatch.setenv(sparse.ORDERING_VARIABLE, "colamd")
    assert sparse.superlu_options()["permc_spec"] == "COLAMD"
    A = _saddle_system()
    b = np.ones(A.shape[0])
    np.testing.assert_allclose(sparse.factorize(A).solve(b), np.linalg.solve(A.toarray(), b),
                               rtol=1e-9)


def test_superlu_pivot_check_names_the_singular_column():
    A = sp.csc_matrix(np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1e-20]]))
    with pytest.raises(sparse.SingularMatrixError) as info:
        sparse.factorize(A, "superlu", pivot_scale=np.ones(3))
    assert info.value.columns.tolist() == [2]
    sparse.factorize(A, "superlu")  # without a scale the tiny pivot is accepted


@pytest.mark.parametrize("backend", sparse.BACKENDS)
def test_singular_iteration_matrix_raises_convergence_error(backend):
    if backend not in sparse.available_backends():
        pytest.skip(f"{backend} not installed")
    A = sp.csc_matrix(np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    with pytest.raises(ConvergenceError) as info:
        Factorization(A, backend=backend).solve(np.array([1.0, 2.0, 3.0]))
    assert info.value.reason == "singular system"


def test_restricted_matrix_is_identity_on_fixed_equations():
    K = sp.csr_matrix(np.arange(1.0, 17.0).reshape(4, 4))
    dense = restricted_matrix(K, np.array([1, 3])).toarray()
    expected = np.arange(1.0, 17.0).reshape(4, 4)
    expected[[1, 3], :] = 0.0
    expected[:, [1, 3]] = 0.0
    expected[1, 1] = expected[3, 3] = 1.0
    np.testing.assert_array_equal(dense, expected)


@pytest.mark.parametrize("implicit", [False, True])
def test_augmented_matrix_matches_its_dense_block_definition(implicit):
    rng = np.random.default_rng(3)
    n_eq, n_pairs = 12, 4
    K = sp.random(n_eq, n_eq, density=0.4, random_state=rng) + sp.eye(n_eq)
    C = sp.random(2 * n_pairs, n_eq, density=0.3, random_state=rng).tocsr()
    fixed = np.array([0, 5])
    state = replace(GapState.initial(n_pairs), state=np.array([FIXED, SLIP, FREE, SLIP]),
                    lam_T=np.array([0.0, 2.0, 0.0, -1.0]))
    mu = 0.5
    A = augmented_matrix(K, C, state, fixed, mu, implicit).toarray()
    # eq. 3.35 written out: fixed equations are identity rows/columns
    free = np.ones(n_eq)
    free[fixed] = 0.0
    K_r = np.diag(free) @ K.toarray() @ np.diag(free) + np.diag(1.0 - free)
    active = np.array([1, 1, 1, 0, 0, 0, 1, 0], dtype=bool)  # N, T per pair
    upper = active | (implicit & np.array([0, 0, 0, 1, 0, 0, 0, 1], dtype=bool))
    C_a = np.diag(active.astype(float)) @ C.toarray() @ np.diag(free)
    C_u = np.diag(upper.astype(float)) @ C.toarray() @ np.diag(free)
    D = np.diag((~active).astype(float))
    if implicit:
        D[3, 2], D[7, 6] = mu, -mu  # sign(lam_T) mu on the SLIP pairs' tangential rows
    np.testing.assert_array_equal(A, np.block([[K_r, C_u.T], [C_a, D]]))
    assert not np.any(augmented_matrix(K, C, state, fixed, mu, implicit).data == 0.0)
    b = rng.random(A.shape[0])
    np.testing.assert_allclose(factorize(A).solve(b), np.linalg.solve(A, b), rtol=1e-8)
