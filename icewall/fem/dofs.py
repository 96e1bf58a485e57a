"""Node dofs -> equation numbers, with optional ties (perfect bond) between coincident nodes."""

from __future__ import annotations

import numpy as np


class DofMap:
    """Equation numbering of the 2 dofs per node; tied slave nodes share their master's equations.

    Without ties the numbering is the global dof numbering, equation = 2 * node + direction.
    With ties the non-slave nodes keep their order and are numbered consecutively. Chains of
    ties (a slave that is also a master) resolve to the root master.
    """

    def __init__(self, n_nodes: int, ties: np.ndarray | None = None) -> None:
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
        root = np.arange(self.n_nodes)
        root[ties[:, 1]] = ties[:, 0]
        # resolve chains master <- slave <- slave ... by pointer jumping (log2 n steps)
        for _ in range(int(np.log2(max(self.n_nodes, 2))) + 2):
            nxt = root[root]
            if np.array_equal(nxt, root):
                break
            root = nxt
        is_slave = np.zeros(self.n_nodes, dtype=bool)
        is_slave[ties[:, 1]] = True
        if np.any(is_slave[root]):
            raise ValueError("node ties contain a cycle")
        is_master = root == np.arange(self.n_nodes)
        rank = np.cumsum(is_master) - 1  # equation-node number of each independent node
        node_rank = rank[root]
        self.node_equations = 2 * node_rank[:, None] + np.arange(2)  # (n_nodes, 2)
        self.n_equations = int(2 * is_master.sum())

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
