"""The assembled consistent tangent (issue 19): with `evaluate(..., tangent=True)` the stiffness
is d f_int / d u of the structure, checked against central differences of the internal forces
on a small concrete-and-steel block whose committed state is cracked and crushed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.fem.assembly import Assembler
from icewall.fem.dofs import DofMap
from icewall.fem.kinematics import element_kinematics, gauss_point_spacing
from icewall.fem.quadrature import gauss_rule
from icewall.materials import concrete_compiled
from icewall.mesh.structured import rectangle_mesh
from icewall.model.description import ModelDescription
from icewall.model.materials import build_groups
from icewall.model.structure import Structure

DECK = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"
X0 = 100.0  # the block's left edge (axisymmetric: its inner radius)


def _block(formulation: str) -> tuple[Structure, DofMap, np.ndarray]:
    """3 x 2 quad8 block 300 x 100 mm: concrete over a bottom row of steel (CF-4 materials)."""
    deck = load_deck(DECK, [f"analysis.formulation={formulation}",
                            "materials.steel.formulation=same"]).deck
    mesh = rectangle_mesh(X0, X0 + 300.0, 0.0, 100.0, 3, 2, cell_type="quad8")
    dofs = DofMap(mesh.n_nodes)
    kin = element_kinematics(mesh.points, mesh.cells, "quad8", gauss_rule(3), formulation,
                             381.0, dofs)
    material = np.where(np.arange(6) % 2 == 0, "steel", "concrete")  # cells are x-major
    groups = build_groups(ModelDescription.of_deck(deck), material,
                          gauss_point_spacing(mesh.points, mesh.cells, 3), 9)
    return Structure(kin, Assembler(kin.dofs, dofs.n_equations), groups), dofs, mesh.points


def _field(dofs: DofMap, points: np.ndarray, curvature: float, shear: float,
           noise: float, seed: int) -> np.ndarray:
    """Bending about y = 62 (the concrete cracks below it and crushes at the top, the steel
    yields), a shear that turns the axes, and random noise."""
    x, y = points[:, 0] - X0, points[:, 1]
    u = np.zeros(dofs.n_equations)
    nodes = np.arange(points.shape[0])
    u[dofs.equations(nodes, 0)] = -curvature * x * (y - 62.0) + shear * y
    u[dofs.equations(nodes, 1)] = (0.5 * curvature * (x * x + 0.5 * (y - 62.0) ** 2)
                                   + 0.3 * shear * x)  # lateral expansion
    return u + noise * np.random.default_rng(seed).normal(size=u.shape)


@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress", "axisymmetric"])
def test_tangent_stiffness_is_the_derivative_of_the_internal_forces(formulation):
    structure, dofs, points = _block(formulation)
    committed = structure.evaluate(_field(dofs, points, 1.2e-4, 0.0, 2e-4, 1),
                                   structure.initial_states()).states
    concrete = structure.groups[[g.name for g in structure.groups].index("concrete")]
    state = committed[structure.groups.index(concrete)]
    assert state.cracked.any() and state.crushed.any()  # a damaged committed state

    u = _field(dofs, points, 1.3e-4, 3e-4, 2e-4, 2)  # further, with the axes turning
    K = structure.stiffness(structure.evaluate(u, committed, tangent=True)).toarray()
    du = np.random.default_rng(3).normal(size=u.shape) * 1e-3
    h = 1e-4
    plus = structure.evaluate(u + h * du, committed).internal_force
    minus = structure.evaluate(u - h * du, committed).internal_force
    expected = (plus - minus) / (2.0 * h)
    assert np.linalg.norm(K @ du - expected) <= 1e-5 * np.linalg.norm(expected)
    # the iteration matrix of the default (secant-coaxial) is not that derivative
    secant = structure.stiffness(structure.evaluate(u, committed)).toarray()
    assert np.linalg.norm(secant @ du - expected) > 1e-3 * np.linalg.norm(expected)
    assert np.abs(K - K.T).max() > 1e-6 * np.abs(K).max()  # not symmetrised


def test_compiled_and_numpy_kernels_give_the_same_tangent(monkeypatch):
    if not concrete_compiled.available("plane_strain", "corotational"):
        pytest.skip("numba is not installed")
    stiffness = {}
    for kernel in ("numpy", "numba"):
        monkeypatch.setenv(concrete_compiled.KERNEL_VARIABLE, kernel)
        structure, dofs, points = _block("plane_strain")
        assert structure.groups[0].law.kernel == kernel
        committed = structure.evaluate(_field(dofs, points, 1.2e-4, 0.0, 2e-4, 1),
                                       structure.initial_states()).states
        u = _field(dofs, points, 1.3e-4, 3e-4, 2e-4, 2)
        stiffness[kernel] = structure.stiffness(structure.evaluate(u, committed,
                                                                   tangent=True)).toarray()
    scale = np.abs(stiffness["numpy"]).max()
    np.testing.assert_allclose(stiffness["numba"], stiffness["numpy"], atol=1e-7 * scale)


def test_frozen_points_have_no_consistent_tangent():
    structure, dofs, _ = _block("plane_strain")
    n = structure.groups[0].cells.size * 9
    frozen = (np.zeros(n, bool), None)
    with pytest.raises(ValueError, match="frozen"):
        structure.evaluate(np.zeros(dofs.n_equations), structure.initial_states(),
                           frozen=frozen, tangent=True)
    plain = structure.evaluate(np.zeros(dofs.n_equations), structure.initial_states(),
                               frozen=frozen)
    with pytest.raises(ValueError, match="frozen"):
        structure.with_tangent(plain)


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
@pytest.mark.parametrize("formulation", ["plane_strain", "plane_stress", "axisymmetric"])
def test_the_tangent_of_an_evaluation_is_the_tangent_evaluation_bit_for_bit(
        formulation, kernel, monkeypatch):
    """Structure.with_tangent (the Newton scheme's line search evaluates without the tangent
    and adds it where a matrix is built) gives what evaluate(..., tangent=True) gives at the
    same displacements, and leaves the evaluation it was given alone."""
    if kernel == "numba" and not concrete_compiled.available(formulation, "corotational"):
        pytest.skip(f"no compiled concrete kernel for {formulation} here")
    monkeypatch.setenv(concrete_compiled.KERNEL_VARIABLE, kernel)
    structure, dofs, points = _block(formulation)
    committed = structure.evaluate(_field(dofs, points, 1.2e-4, 0.0, 2e-4, 1),
                                   structure.initial_states()).states
    u = _field(dofs, points, 1.3e-4, 3e-4, 2e-4, 2)
    whole = structure.evaluate(u, committed, tangent=True)
    plain = structure.evaluate(u, committed)
    secant = plain.moduli.copy()
    added = structure.with_tangent(plain)
    assert added.tangent and whole.tangent and not plain.tangent
    np.testing.assert_array_equal(added.moduli, whole.moduli)
    np.testing.assert_array_equal(added.stress, whole.stress)
    np.testing.assert_array_equal(added.internal_force, whole.internal_force)
    assert not np.array_equal(secant, whole.moduli)  # the secant moduli are not the tangent
    np.testing.assert_array_equal(plain.moduli, secant)  # untouched
    assert structure.with_tangent(added) is added
