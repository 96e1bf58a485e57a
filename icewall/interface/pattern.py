"""The sparsity pattern of the augmented gap-element matrix (eq. 3.35), computed once.

Every entry the matrix can ever hold, for any pair states, is a slot of one canonical CSC
pattern: the stiffness (and stabilisation) block, C below it and C^T beside it, the diagonal
of the multiplier block and the Coulomb coupling of implicit slip. One iteration then only
writes values into the slots and drops the zeros, instead of building and sorting a new
matrix (the pair states decide which slots hold a value).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from icewall.interface.gap import SLIP, GapState


def _slots(keys: np.ndarray, rows: np.ndarray, cols: np.ndarray, m: int) -> np.ndarray:
    """Positions in the CSC data array (sorted `keys` = col * m + row) of entries (rows, cols)."""
    return np.searchsorted(keys, cols.astype(np.int64) * m + rows)


def canonical_csr(matrix: sp.spmatrix) -> sp.csr_matrix:
    """A CSR copy with sorted indices and no duplicates (the order `matrix` fills slots in)."""
    csr = sp.csr_matrix(matrix, copy=True)
    csr.sum_duplicates()
    return csr


def fixed_mask(fixed: np.ndarray | None, size: int) -> np.ndarray:
    """(size,) bool: True at the supported equations `fixed` (none if None)."""
    mask = np.zeros(size, dtype=bool)
    if fixed is not None:
        mask[np.asarray(fixed, dtype=int)] = True
    return mask


def _coo(matrix: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, cols, values) of `matrix` in canonical CSR order."""
    csr = canonical_csr(matrix)
    rows = np.repeat(np.arange(csr.shape[0]), np.diff(csr.indptr))
    return rows, csr.indices.astype(np.int64), csr.data


class AugmentedPattern:
    """Slots of [[K (+ k C^T C), C^T], [C, D]] for a stiffness pattern, C and the supports.

    `matrix(K, ...)` equals icewall.interface.augmented.augmented_matrix for a K with this
    pattern (canonical CSR, as the assembler gives it): supported equations are identity rows
    and columns, C's rows enter below (active rows) and beside (active and implicit-slip rows)
    the stiffness, inactive rows are identity rows, and stored zeros are dropped.
    """

    def __init__(self, K: sp.spmatrix, C: sp.spmatrix, fixed: np.ndarray,
                 stabilisation: sp.spmatrix | None = None) -> None:
        n_eq, n_rows = K.shape[0], C.shape[0]
        m = self.size = n_eq + n_rows
        self.n_eq = n_eq
        K = canonical_csr(K)
        self._k_indptr, self._k_indices = K.indptr.copy(), K.indices.copy()
        k_rows, k_cols, _ = _coo(K)
        c_rows, c_cols, self._c_values = _coo(C)
        s_rows, s_cols, s_values = _coo(stabilisation if stabilisation is not None
                                        else sp.csr_matrix((n_eq, n_eq)))
        self._s_values = s_values
        diagonal = np.arange(m, dtype=np.int64)
        slip_rows = n_eq + 2 * np.arange(n_rows // 2, dtype=np.int64)
        rows = np.concatenate([k_rows, s_rows, n_eq + c_rows, c_cols, diagonal, slip_rows + 1])
        cols = np.concatenate([k_cols, s_cols, c_cols, n_eq + c_rows, diagonal, slip_rows])
        keys = np.unique(cols * m + rows)
        self.indices = (keys % m).astype(np.int32)
        self.indptr = np.searchsorted(keys, np.arange(m + 1, dtype=np.int64) * m).astype(np.int32)
        self._k = _slots(keys, k_rows, k_cols, m)
        self._s = _slots(keys, s_rows, s_cols, m)
        self._below = _slots(keys, n_eq + c_rows, c_cols, m)  # C_a: row r of C under K
        self._beside = _slots(keys, c_cols, n_eq + c_rows, m)  # C_u^T: beside K
        self._multiplier_diagonal = _slots(keys, diagonal[n_eq:], diagonal[n_eq:], m)
        self._slip = _slots(keys, slip_rows + 1, slip_rows, m)
        self._c_row, self._c_free = c_rows, ~fixed_mask(fixed, n_eq)[c_cols]
        # entries in a supported row or column of the stiffness block, and its diagonal there
        is_fixed = fixed_mask(fixed, m)
        all_rows, all_cols = self.indices, np.repeat(diagonal, np.diff(self.indptr))
        self._supported = np.flatnonzero(is_fixed[all_rows] | is_fixed[all_cols])
        self._supported_diagonal = _slots(keys, diagonal[is_fixed], diagonal[is_fixed], m)
        self.nnz = keys.size

    def fits(self, K: sp.spmatrix) -> bool:
        """Whether K (CSR) has the stiffness pattern this was built for."""
        return (getattr(K, "format", "") == "csr" and K.indptr.shape == self._k_indptr.shape
                and K.nnz == self._k_indices.size and np.array_equal(K.indptr, self._k_indptr)
                and np.array_equal(K.indices, self._k_indices))

    def matrix(self, K: sp.csr_matrix, active: np.ndarray, upper: np.ndarray,
               state: GapState, mu: float = 0.0, implicit_slip: bool = False,
               stabilisation_factor: float = 0.0,
               diagonal_pad: np.ndarray | None = None) -> sp.csc_matrix:
        """The augmented matrix (canonical CSC, no stored zeros) for K with this pattern.

        active: (2n,) rows enforced below K; upper: rows whose C^T stands beside K;
        diagonal_pad: (2n,) added to the multiplier diagonal (e.g. redundant active rows)."""
        data = np.zeros(self.nnz)
        data[self._k] = K.data
        if stabilisation_factor:
            data[self._s] += stabilisation_factor * self._s_values
        data[self._supported] = 0.0
        data[self._supported_diagonal] = 1.0
        data[self._below] = np.where(active[self._c_row] & self._c_free, self._c_values, 0.0)
        data[self._beside] = np.where(upper[self._c_row] & self._c_free, self._c_values, 0.0)
        diagonal = (~active).astype(float)
        if diagonal_pad is not None:
            diagonal = diagonal + diagonal_pad
        data[self._multiplier_diagonal] = diagonal
        if implicit_slip:
            data[self._slip] = np.where(state.state == SLIP, np.sign(state.lam_T) * mu, 0.0)
        A = sp.csc_matrix((data, self.indices.copy(), self.indptr.copy()),
                          shape=(self.size, self.size))
        A.has_sorted_indices = True
        A.eliminate_zeros()
        return A
