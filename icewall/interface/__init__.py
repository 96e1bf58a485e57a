"""Steel-concrete interface gap elements (thesis §3.3, corrected by errata §1.2).

`gap`: pair states (FIXED / SLIP / FREE), the constraint matrix C of eq. 3.39, the state
decision matrix (Table 3.2), new-step slip reset, fixed points (§4.3.2) and friction work.
`augmented`: the symmetric saddle-point iteration matrix and right-hand sides (eq. 3.35,
Tables 3.1 and 3.3 in total form) and their factorisation for two right-hand sides.
"""

from icewall.interface.augmented import (
    AugmentedFactor,
    augmented_matrix,
    augmented_rhs,
    factorize,
    interface_forces,
    reference_rhs,
    split_solution,
)
from icewall.interface.fixed_points import choose_fixed_points
from icewall.interface.gap import (
    FIXED,
    FREE,
    SLIP,
    GapState,
    constraint_matrix,
    count_states,
    friction_work_increment,
    new_step,
    relative_displacement,
    update_states,
)

__all__ = [
    "FIXED", "FREE", "SLIP", "AugmentedFactor", "GapState", "augmented_matrix", "augmented_rhs",
    "choose_fixed_points", "constraint_matrix", "count_states", "factorize",
    "friction_work_increment", "interface_forces", "new_step", "reference_rhs",
    "relative_displacement", "split_solution", "update_states",
]
