"""Sparse assembly with a CSR pattern computed once per dof layout."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


class Assembler:
    """Scatters element blocks into a global CSR matrix / vector of fixed sparsity pattern.

    The COO entries of all element blocks are sorted into CSR order once, at construction;
    `matrix` then only sums the block data into the pattern with np.bincount.
    """

    def __init__(self, dofs: np.ndarray, n_dofs: int) -> None:
        self.dofs = np.asarray(dofs, dtype=np.int64)
        self.n_dofs = int(n_dofs)
        if self.dofs.ndim != 2:
            raise ValueError(f"dofs must be (n_el, nd), got shape {self.dofs.shape}")
        if self.dofs.size and (self.dofs.min() < 0 or self.dofs.max() >= self.n_dofs):
            raise ValueError(f"dof ids out of range [0, {self.n_dofs})")
        n_el, nd = self.dofs.shape
        rows = np.broadcast_to(self.dofs[:, :, None], (n_el, nd, nd)).ravel()
        cols = np.broadcast_to(self.dofs[:, None, :], (n_el, nd, nd)).ravel()
        keys, self._slot = np.unique(rows * self.n_dofs + cols, return_inverse=True)
        self._slot = self._slot.ravel()  # COO entry -> CSR data slot
        self.nnz = int(keys.size)
        self._indices = (keys % self.n_dofs).astype(np.int32 if self.n_dofs < 2**31 else np.int64)
        counts = np.bincount(keys // self.n_dofs, minlength=self.n_dofs)
        self._indptr = np.concatenate([[0], np.cumsum(counts)]).astype(self._indices.dtype)

    def matrix(self, blocks: np.ndarray) -> sp.csr_matrix:
        """Global matrix (n_dofs, n_dofs) from element blocks (n_el, nd, nd)."""
        blocks = np.asarray(blocks, dtype=float)
        if blocks.size != self._slot.size:
            raise ValueError(f"blocks shape {blocks.shape} does not match the dof layout "
                             f"{self.dofs.shape}")
        data = np.bincount(self._slot, weights=blocks.ravel(), minlength=self.nnz)
        K = sp.csr_matrix((data, self._indices.copy(), self._indptr.copy()),
                          shape=(self.n_dofs, self.n_dofs))
        K.has_sorted_indices = True
        return K

    def vector(self, blocks: np.ndarray) -> np.ndarray:
        """Global vector (n_dofs,) from element vectors (n_el, nd)."""
        return np.bincount(self.dofs.ravel(), weights=np.asarray(blocks, dtype=float).ravel(),
                           minlength=self.n_dofs)
