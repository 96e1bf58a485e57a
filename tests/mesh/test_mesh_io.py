"""Mesh files: every region and named set survives as a physical group; spacing report."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np

from icewall.deck.load import load_deck
from icewall.mesh.build import build_mesh
from icewall.mesh.io import mesh_report, write_mesh

DECKS = Path(__file__).resolve().parents[2] / "decks"


def test_written_files_carry_regions_and_sets(tmp_path):
    mesh = build_mesh(load_deck(DECKS / "cf4.yaml").deck)
    paths = write_mesh(mesh, tmp_path / "cf4", ["msh", "vtu", "xdmf"])
    assert [p.suffix for p in paths] == [".msh", ".vtu", ".xdmf"]
    msh = meshio.read(tmp_path / "cf4.msh")
    names = set(msh.field_data)
    assert {r.name for r in mesh.regions} <= names
    assert set(mesh.node_sets) | set(mesh.edge_sets) <= names
    quads = msh.get_cells_type("quad8")
    assert quads.shape == mesh.cells.shape
    assert np.allclose(msh.points[:, :2], mesh.points)  # double nodes kept, order kept
    xdmf = meshio.read(tmp_path / "cf4.xdmf")
    assert xdmf.get_cells_type("quad8").shape == mesh.cells.shape


def test_spacing_report_lists_every_region():
    deck = load_deck(DECKS / "cf4.yaml").deck
    mesh = build_mesh(deck)
    text = mesh_report(mesh, 3)
    for region in mesh.regions:
        assert region.name in text
    assert f"{mesh.n_nodes} nodes" in text
