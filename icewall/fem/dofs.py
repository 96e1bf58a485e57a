"""Node dofs -> equation numbers, with optional ties (perfect bond) between coincident nodes."""

from __future__ import annotations

import numpy as np


class DofMap:
    """Equation numbering of the 2 dofs per node; tied slave nodes share their master's equations,
    and each `shared` set of node dofs shares one equation (a rigid head moving as one).

    Without ties or shared sets the numbering is the global dof numbering, equation = 2 * node +
    direction. Otherwise the independent dofs keep their order and are numbered consecutively.
    Chains of ties (a slave that is also a master) resolve to the root master. `shared` holds
    (nodes, direction) pairs: those nodes' dofs in that direction take the equation of the
    first node's.
    """

    def __init__(self, n_nodes: int, ties: np.ndarray | None = None,
                 shared: tuple[tuple[np.ndarray, int], ...] = ()) -> None:
        self.n_nodes = int(n_nodes)
        ties = np.zeros((0, 2), dtype=int) if ties is None else np.asarray(ties, dtype=int)
        ties = ties.reshape(-1, 2)
        if ties.size and (ties.min() < 0 or ties.max() >= self.n_nodes):
            raise ValueError(f"tie node ids out of range [0, {self.n_nodes})")
        if np.any(ties[:, 0] == ties[:, 1]):
            raise ValueError("a node cannot be tied to itself")
        if np.unique(ties[:, 1]).size != ties.shape[0]:
            raise ValueError("a slave node is tied to more than one master")
        self.ties = ties
        root = _tie_roots(self.n_nodes, ties)
        dof_root = (2 * root[:, None] + np.arange(2)).ravel()
        for nodes, direction in shared:
            dofs = 2 * np.asarray(nodes, dtype=int).ravel() + int(direction)
            if dofs.size and (dofs.min() < 0 or dofs.max() >= 2 * self.n_nodes):
                raise ValueError(f"shared node ids out of range [0, {self.n_nodes})")
            if dofs.size:
                dof_root[np.isin(dof_root, dof_root[dofs])] = dof_root[dofs[0]]
        is_master = dof_root == np.arange(dof_root.size)
        rank = np.cumsum(is_master) - 1  # equation number of each independent dof
        self.node_equations = rank[dof_root].reshape(self.n_nodes, 2)
        self.n_equations = int(is_master.sum())

    def equations(self, nodes: np.ndarray, direction: int | None = None) -> np.ndarray:
        """Equation ids of `nodes` in `direction` (0 = x, 1 = y) or both (flattened, node-major)."""
        eqs = self.node_equations[np.asarray(nodes, dtype=int)]
        return (eqs if direction is None else eqs[..., direction]).ravel()

    def element_dofs(self, cells: np.ndarray) -> np.ndarray:
        """Element equation ids (n_el, 2 * nn), node-major: [u_x, u_y] per node."""
        cells = np.asarray(cells, dtype=int)
        return self.node_equations[cells].reshape(cells.shape[0], -1)

    def expand(self, u_eq: np.ndarray) -> np.ndarray:
        """Nodal displacements (n_nodes, 2) from the equation vector (n_eq,)."""
        return np.asarray(u_eq)[self.node_equations]

    def restrict(self, f_nodal: np.ndarray) -> np.ndarray:
        """Equation vector (n_eq,) from a nodal vector (2 * n_nodes,), summing tied nodes."""
        f = np.asarray(f_nodal, dtype=float).reshape(-1)
        return np.bincount(self.node_equations.ravel(), weights=f, minlength=self.n_equations)


def _tie_roots(n_nodes: int, ties: np.ndarray) -> np.ndarray:
    """The root master of every node under `ties` (master, slave), by pointer jumping (log2 n
    steps); a cycle is an error."""
    root = np.arange(n_nodes)
    root[ties[:, 1]] = ties[:, 0]
    for _ in range(int(np.log2(max(n_nodes, 2))) + 2):
        nxt = root[root]
        if np.array_equal(nxt, root):
            break
        root = nxt
    is_slave = np.zeros(n_nodes, dtype=bool)
    is_slave[ties[:, 1]] = True
    if np.any(is_slave[root]):
        raise ValueError("node ties contain a cycle")
    return root
