"""Wall meshes: structure, interface node pairs and normals, named sets, determinism."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from icewall.deck.load import load_deck
from icewall.mesh.build import build_mesh
from icewall.mesh.mesh import CONCRETE
from icewall.model.loads import patch_load_vector

DECKS = Path(__file__).resolve().parents[2] / "decks"


def _mesh(name: str, *overrides: str):
    deck = load_deck(DECKS / name, overrides).deck
    return deck, build_mesh(deck)


@pytest.fixture(scope="module", params=["cf4.yaml", "tf1.yaml", "vtt3.yaml"])
def deck_and_mesh(request):
    return _mesh(request.param)


def test_same_deck_same_mesh():
    _, a = _mesh("cf4.yaml")
    _, b = _mesh("cf4.yaml")
    assert np.array_equal(a.points, b.points)
    assert np.array_equal(a.cells, b.cells)
    assert np.array_equal(a.interface_pairs, b.interface_pairs)


def test_elements_are_counter_clockwise_and_quad8(deck_and_mesh):
    _, mesh = deck_and_mesh
    assert mesh.cells.shape[1] == 8
    c = mesh.points[mesh.cells[:, :4]]
    area = 0.5 * np.sum(c[..., 0] * np.roll(c[..., 1], -1, 1) - np.roll(c[..., 0], -1, 1)
                        * c[..., 1], axis=1)
    assert np.all(area > 0)
    # mid-side nodes at the middle of their (straight) edges
    for mid, (a, b) in zip(range(4, 8), [(0, 1), (1, 2), (2, 3), (3, 0)], strict=True):
        expected = 0.5 * (mesh.points[mesh.cells[:, a]] + mesh.points[mesh.cells[:, b]])
        assert np.allclose(mesh.points[mesh.cells[:, mid]], expected)


def test_no_steel_node_is_shared_with_concrete(deck_and_mesh):
    _, mesh = deck_and_mesh
    concrete = mesh.cells_of_kind(CONCRETE)
    shared = np.intersect1d(mesh.cells[concrete], mesh.cells[~concrete])
    assert shared.size == 0


def test_interface_pairs_are_coincident_with_consistent_normals(deck_and_mesh):
    _, mesh = deck_and_mesh
    pairs, normals = mesh.interface_pairs, mesh.interface_normals
    assert len(pairs) > 0
    concrete_nodes = np.unique(mesh.cells[mesh.cells_of_kind(CONCRETE)])
    assert np.all(np.isin(pairs[:, 1], concrete_nodes))
    assert not np.any(np.isin(pairs[:, 0], concrete_nodes))
    assert np.allclose(mesh.points[pairs[:, 0]], mesh.points[pairs[:, 1]])
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    # A small step along the normal from an interface node enters concrete; a step back
    # enters steel (cells tested by their bounding boxes; all cells are axis-aligned).
    corners = mesh.points[mesh.cells[:, :4]]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    is_concrete = mesh.cells_of_kind(CONCRETE)

    def kinds_at(p):
        inside = np.all((p >= lo - 1e-9) & (p <= hi + 1e-9), axis=1)
        return set(is_concrete[inside].tolist())

    for node, n in zip(pairs[:, 1], normals, strict=True):
        p = mesh.points[node]
        assert kinds_at(p + 0.1 * n) == {True}
        assert kinds_at(p - 0.1 * n) == {False}
    # off the corners the normals are axis-aligned
    plain = normals[~mesh.interface_corner]
    assert np.allclose(np.sort(np.abs(plain), axis=1), [0.0, 1.0])


def test_every_concrete_boundary_node_on_steel_is_paired(deck_and_mesh):
    deck, mesh = deck_and_mesh
    concrete_nodes = np.unique(mesh.cells[mesh.cells_of_kind(CONCRETE)])
    steel_nodes = np.unique(mesh.cells[~mesh.cells_of_kind(CONCRETE)])
    # coincident steel node exists <=> node is paired
    p = mesh.points
    key = {tuple(np.round(p[i], 6)) for i in steel_nodes}
    touching = [i for i in concrete_nodes if tuple(np.round(p[i], 6)) in key]
    assert sorted(touching) == sorted(mesh.interface_pairs[:, 1].tolist())


def test_bonded_wall_shares_nodes_and_has_no_pairs():
    _, mesh = _mesh("cf4.yaml", "materials.interface.model=bonded")
    assert len(mesh.interface_pairs) == 0
    concrete = mesh.cells_of_kind(CONCRETE)
    assert np.intersect1d(mesh.cells[concrete], mesh.cells[~concrete]).size > 0


def test_cf4_named_sets():
    deck, mesh = _mesh("cf4.yaml")
    control = mesh.points[mesh.node_sets["control"][0]]
    assert np.allclose(control, [0.0, 250.0])
    support = mesh.points[mesh.node_sets["support_1"][0]]
    assert np.allclose(support, [750.0, -25.0])  # centre of the bearing plate's underside
    assert np.allclose(mesh.points[mesh.node_sets["symmetry"], 0], 0.0)
    # Unit jack load on 2 full patches and the half patch at midspan: total 2.5 N down.
    f = patch_load_vector(deck, mesh).reshape(-1, 2)
    assert f[:, 0].sum() == pytest.approx(0.0, abs=1e-12)
    assert f[:, 1].sum() == pytest.approx(-2.5)


@pytest.mark.parametrize("k", [0, 1, 4])
def test_a_patch_flush_with_the_wall_end_survives_the_round_off_widening(k):
    """CF-4's wall-end station is flush with the end (1058 + 25 = 1083). A round-off
    realization widens every patch by k 1e-8 of its width (up to 1e-6 mm past the end): the
    deck stays valid, the mesh gets no line past the end, and the load changes by the
    widening alone."""
    width = 50.0 * (1 + k * 1e-8)
    deck, mesh = _mesh("cf4.yaml", f"loads.patches.width={width!r}")
    assert mesh.points[:, 0].max() == pytest.approx(deck.geometry.half_length, abs=1e-12)
    f = patch_load_vector(deck, mesh).reshape(-1, 2)
    assert f[:, 1].sum() == pytest.approx(-2.5, rel=1e-7)


@pytest.mark.parametrize("name", ["cf4.yaml", "cf13.yaml", "tf1.yaml", "vtt3.yaml"])
def test_a_round_off_realization_keeps_the_mesh(name):
    """Realization k widens the load patches by k 1e-8 of their width (icewall.analysis.sweep):
    a round-off perturbation, so the mesh keeps its nodes, and they move by no more than the
    patch edges do (k 25e-8 mm; a 50 mm patch interval used to split into two elements, 794 ->
    821 nodes on CF-4)."""
    deck, base = _mesh(name)
    for k in (1, 2, 4):
        width = deck.loads.patches.width * (1 + k * 1e-8)
        _, mesh = _mesh(name, f"loads.patches.width={width!r}")
        assert mesh.points.shape == base.points.shape
        assert np.abs(mesh.points - base.points).max() <= k * 25e-8 * (1 + 1e-6)


def test_quad4_and_element_size_control_the_mesh():
    _, coarse = _mesh("cf4.yaml", "analysis.element=quad4")
    assert coarse.cells.shape[1] == 4
    _, fine = _mesh("cf4.yaml", "analysis.element_size=25")
    _, base = _mesh("cf4.yaml", "analysis.element_size=75")
    assert fine.n_cells > 4 * base.n_cells
    core = fine.cells_of_kind(CONCRETE)
    pts = fine.points[fine.cells[core][:, :4]]
    size = pts.max(axis=1) - pts.min(axis=1)
    assert size.max() <= 25.0 + 1e-9


def test_full_model_is_symmetric():
    _, mesh = _mesh("cf4.yaml", "geometry.model=full", "geometry.supports=[{x: 750.0, "
                    "restraint: pin}]")
    x = np.sort(np.round(mesh.points[:, 0], 6))
    assert np.allclose(x, -x[::-1])
    assert "symmetry" not in mesh.node_sets
    assert len(mesh.node_sets["support_1"]) == 2
