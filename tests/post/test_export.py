"""ParaView export read back with meshio and checked against the HDF5 (read with h5py)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
from click.testing import CliRunner

from icewall.cli import main


def test_vtu_series_holds_the_stored_fields(small_result, tmp_path):
    out = tmp_path / "view" / "run.pvd"
    result = CliRunner().invoke(main, ["export", small_result, "-o", str(out)])
    assert result.exit_code == 0, result.output
    entries = ET.parse(out).getroot().findall("./Collection/DataSet")
    with h5py.File(small_result, "r") as f:
        steps = sorted(f["steps"])
        points, cells = f["mesh/points"][:], f["mesh/cells"][:]
        assert len(entries) == len(steps)
        for entry, name in zip(entries, steps, strict=True):
            g = f["steps"][name]
            assert float(entry.get("timestep")) == g.attrs["control_displacement"]
            m = meshio.read(out.parent / entry.get("file"))
            assert np.allclose(m.points[:, :2], points)
            assert m.cells[0].type == "quad8" and np.array_equal(m.cells[0].data, cells)
            assert np.allclose(m.point_data["displacement"][:, :2], g["displacement"][:])
            stress = g["gauss/stress"][:]
            assert np.allclose(m.cell_data["stress_xy_cellmean"][0], stress[..., 3].mean(axis=1))
            cracked = (g["gauss/concrete_flags"][:][..., :2] != 0).any(axis=-1).mean(axis=1)
            assert np.allclose(m.cell_data["cracked_in_plane_fraction"][0], cracked)
            pairs, state = f["mesh/interface/pairs"][:], g["interface/state"][:]
            assert np.array_equal(m.point_data["interface_state"][pairs[:, 1]], state)
            others = np.setdiff1d(np.arange(len(points)), pairs.ravel())
            assert np.all(m.point_data["interface_state"][others] == -1)


def test_export_refuses_another_suffix(small_result, tmp_path):
    result = CliRunner().invoke(main, ["export", small_result, "-o", str(tmp_path / "x.xdmf")])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert ".pvd" in result.output
