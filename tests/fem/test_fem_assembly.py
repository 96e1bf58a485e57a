"""Assembler against a naive dense assembly; DofMap numbering and ties."""

from __future__ import annotations

import numpy as np
import pytest

from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.mesh.structured import rectangle_mesh


def _naive(dofs, blocks, n):
    K = np.zeros((n, n))
    for e, d in enumerate(dofs):
        K[np.ix_(d, d)] += blocks[e]
    return K


@pytest.mark.parametrize("cell_type", ["quad4", "quad8"])
def test_matrix_and_vector_equal_naive_assembly(cell_type):
    mesh = rectangle_mesh(0.0, 3.0, 0.0, 2.0, 3, 2, cell_type)
    dofs = (2 * mesh.cells[:, :, None] + np.arange(2)).reshape(mesh.n_cells, -1)
    n, nd = 2 * mesh.n_nodes, dofs.shape[1]
    rng = np.random.default_rng(0)
    asm = Assembler(dofs, n)
    for _ in range(3):  # repeated calls with new data reuse the one pattern
        blocks = rng.normal(size=(mesh.n_cells, nd, nd))
        K = asm.matrix(blocks)
        np.testing.assert_allclose(K.toarray(), _naive(dofs, blocks, n), rtol=1e-14,
                                   atol=1e-14)
        assert K.has_sorted_indices and K.nnz == asm.nnz
        vec = rng.normal(size=(mesh.n_cells, nd))
        expected = np.zeros(n)
        np.add.at(expected, dofs, vec)
        np.testing.assert_allclose(asm.vector(vec), expected, rtol=1e-14, atol=1e-14)
    # the pattern arrays are not shared with the returned matrices
    K.indices[:] = 0
    np.testing.assert_allclose(asm.matrix(blocks).toarray(), _naive(dofs, blocks, n),
                               atol=1e-14)


def test_assembler_rejects_mismatched_input():
    dofs = np.array([[0, 1, 2, 3]])
    asm = Assembler(dofs, 4)
    with pytest.raises(ValueError, match="does not match"):
        asm.matrix(np.zeros((2, 4, 4)))
    with pytest.raises(ValueError, match="out of range"):
        Assembler(dofs, 3)


def test_dofmap_without_ties_is_the_global_numbering():
    dm = DofMap(5)
    assert dm.n_equations == 10
    np.testing.assert_array_equal(dm.node_equations.ravel(), np.arange(10))
    np.testing.assert_array_equal(dm.element_dofs(np.array([[4, 1]])), [[8, 9, 2, 3]])


def test_dofmap_ties_share_master_equations_and_sum_forces():
    # nodes 0..5; 4 tied to 1, 5 tied to 4 (a chain: resolves to 1)
    dm = DofMap(6, ties=np.array([[1, 4], [4, 5]]))
    assert dm.n_equations == 8
    np.testing.assert_array_equal(dm.node_equations[4], dm.node_equations[1])
    np.testing.assert_array_equal(dm.node_equations[5], dm.node_equations[1])
    np.testing.assert_array_equal(dm.equations([3], 1), [7])
    f = np.arange(12, dtype=float)
    r = dm.restrict(f)
    assert r[dm.node_equations[1, 0]] == f[2] + f[8] + f[10]  # x forces of nodes 1, 4, 5
    assert r.sum() == f.sum()
    u = dm.expand(np.arange(8.0))
    assert u.shape == (6, 2)
    np.testing.assert_array_equal(u[5], u[1])


def test_dofmap_shared_dofs_take_one_equation_in_their_direction_only():
    # nodes 0..4; the y dofs of nodes 3, 1, 4 move as one (a rigid head), led by node 3
    dm = DofMap(5, shared=((np.array([3, 1, 4]), 1),))
    assert dm.n_equations == 8
    # independent dofs in global order: 0x 0y 1x 2x 2y 3x 3y 4x -> 0..7; 1y and 4y take 3y's
    np.testing.assert_array_equal(dm.node_equations,
                                  [[0, 1], [2, 6], [3, 4], [5, 6], [7, 6]])
    f = np.arange(10, dtype=float)
    assert dm.restrict(f)[6] == f[3] + f[7] + f[9]  # the head's force: the sum of its nodes'
    np.testing.assert_array_equal(dm.expand(np.arange(8.0))[[1, 3, 4], 1], [6.0, 6.0, 6.0])


def test_dofmap_shared_dofs_on_tied_nodes_follow_the_master():
    # node 4 tied to 1; the x dofs of nodes 4 and 2 shared: 1x, 2x and 4x are one equation
    dm = DofMap(5, ties=np.array([[1, 4]]), shared=((np.array([4, 2]), 0),))
    assert dm.n_equations == 7
    assert dm.node_equations[4, 0] == dm.node_equations[1, 0] == dm.node_equations[2, 0]
    assert dm.node_equations[4, 1] == dm.node_equations[1, 1] != dm.node_equations[2, 1]
    with pytest.raises(ValueError, match="out of range"):
        DofMap(3, shared=((np.array([0, 3]), 1),))


@pytest.mark.parametrize("ties", [[[0, 0]], [[0, 1], [2, 1]], [[0, 9]], [[0, 1], [1, 0]]])
def test_dofmap_rejects_bad_ties(ties):
    with pytest.raises(ValueError):
        DofMap(3, ties=np.array(ties))
