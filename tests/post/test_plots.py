"""Plot builders on a small nonlinear run: what is drawn is checked against the stored fields
and closed forms, not against the drawing code itself."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from icewall.cli import main
from icewall.fem.quadrature import gauss_legendre
from icewall.mesh.gauss import gauss_points_xy
from icewall.post.common import step_at
from icewall.post.deformed import auto_scale, interface_motion
from icewall.post.plate_stresses import member_stresses
from icewall.post.trajectories import principal_stresses
from icewall.results.reader import open_result

pytest.importorskip("matplotlib")


def collections(fig, kind):
    return [c for ax in fig.axes for c in ax.collections if type(c).__name__ == kind]


def marker_lines(fig, marker):
    return [ln for ax in fig.axes for ln in ax.lines if ln.get_marker() == marker]


def test_gauss_points_are_the_tensor_rule_in_a_rectangle(small_result):
    with open_result(small_result) as r:
        mesh = r.mesh
    xy = gauss_points_xy(mesh, 3)
    corners = mesh.points[mesh.cells[0, :4]]
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    xi = gauss_legendre(3)[0]
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    expect = np.array([centre + half * (a, b) for a in xi for b in xi])
    # gmsh may number a cell from any corner: compare as sets of points

    def rows(a):
        return sorted(map(tuple, np.round(a, 6)))

    assert np.allclose(rows(xy[0]), rows(expect))


def test_crack_lines_follow_the_stored_orthotropy_axes(small_result):
    from icewall.post.patterns import plot_cracks

    with open_result(small_result) as r:
        step = r.steps[-1]
        flags = r.gauss(step, "concrete_flags") != 0
        beta = r.gauss(step, "orthotropy_angle")[..., 0]
        fig = plot_cracks(r, step)
    (lines,) = collections(fig, "LineCollection")
    seg = np.array(lines.get_segments())
    drawn = np.arctan2(seg[:, 1, 1] - seg[:, 0, 1], seg[:, 1, 0] - seg[:, 0, 0])
    # direction-1 cracks run along axis 2 (beta + 90 deg), direction-2 cracks along axis 1
    expect = np.concatenate([beta[flags[..., 0]] + 0.5 * np.pi, beta[flags[..., 1]]])
    assert len(drawn) == flags[..., 0].sum() + flags[..., 1].sum() > 0
    assert np.allclose(np.sin(drawn - expect), 0.0, atol=1e-9)  # same line (mod pi)
    (out,) = marker_lines(fig, "D")
    (crushed,) = marker_lines(fig, "8")
    assert len(out.get_xdata()) == flags[..., 2].sum()
    assert len(crushed.get_xdata()) == flags[..., 3:6].any(axis=-1).sum() > 0


def test_interface_motion_recomputed_from_displacements_matches_the_solver(small_result):
    with open_result(small_result) as r:
        step = r.steps[-1]
        separation, slip = interface_motion(r.mesh, r.displacement(step))
        assert np.allclose(separation, r.array(step, "interface/gap_N"), atol=1e-12)
        assert np.allclose(slip, r.array(step, "interface/gap_T"), atol=1e-12)
        assert separation.max() > 0.01 and np.abs(slip).max() > 0.01


def test_deformed_shape_is_points_plus_scaled_displacement(small_result):
    from icewall.post.deformed import plot_deformed

    with open_result(small_result) as r:
        step = r.steps[-1]
        moved = r.mesh.points + 3.0 * r.displacement(step)
        first = r.mesh.cells[0, 0]
        fig = plot_deformed(r, step, scale=3.0)
    polys = collections(fig, "PolyCollection")
    drawn = [p.get_paths()[0].vertices[0] for p in polys[1:]]  # after the undeformed outline
    assert any(np.allclose(v, moved[first]) for v in drawn)
    assert "x 3" in fig.axes[0].get_title(loc="left")


def test_auto_scale_is_a_round_number():
    points = np.array([[0.0, 0.0], [1000.0, 0.0]])
    for largest, scale in ((10.0, 5.0), (40.0, 1.0), (0.3, 100.0), (0.04, 1000.0)):
        assert auto_scale(points, np.array([[0.0, -largest]])) == scale


def test_principal_stresses_match_an_eigen_solution():
    rng = np.random.default_rng(3)
    stress = rng.normal(size=(50, 4)) * 10.0
    s1, s2, theta = principal_stresses(stress)
    for k in range(50):
        t = np.array([[stress[k, 0], stress[k, 3]], [stress[k, 3], stress[k, 1]]])
        values, vectors = np.linalg.eigh(t)
        assert np.allclose([s2[k], s1[k]], values)
        direction = np.array([np.cos(theta[k]), np.sin(theta[k])])
        assert np.allclose(t @ direction, s1[k] * direction)


def test_plate_means_of_a_linear_field_are_exact(small_result):
    with open_result(small_result) as r:
        mesh = r.mesh
    xy = gauss_points_xy(mesh, 3)
    stress = np.zeros(xy.shape[:2] + (4,))
    stress[..., 0] = 5.0 + 0.3 * xy[..., 1] + 0.01 * xy[..., 0]  # sigma_xx
    stress[..., 1] = -2.0 + 0.2 * xy[..., 0] + 0.05 * xy[..., 1]  # sigma_yy
    members = member_stresses(mesh, stress, 3)
    assert {"top_plate", "bottom_plate", "diaphragm_1"} <= set(members)
    for name, (axis, stations, mean) in members.items():
        cells = mesh.cell_region == next(g.tag for g in mesh.regions if g.name == name)
        nodes = mesh.points[np.unique(mesh.cells[cells])]
        mid = 0.5 * (nodes.min(axis=0) + nodes.max(axis=0))[1 - axis]  # mid-thickness
        expect = (5.0 + 0.3 * mid + 0.01 * stations if axis == 0
                  else -2.0 + 0.2 * mid + 0.05 * stations)
        assert np.allclose(mean, expect), name


def test_interface_map_counts_match_the_history(small_result):
    from icewall.post.interface_map import plot_interface_map

    with open_result(small_result) as r:
        step = r.steps[-1]
        h = {k: int(v[step - 1]) for k, v in r.history.items() if k.startswith("gap_")}
        fig = plot_interface_map(r, step)
    drawn = {ln.get_label().split(" ")[0]: len(ln.get_xdata()) for ln in fig.axes[0].lines}
    assert drawn == {"stick": h["gap_fixed"], "slip": h["gap_slip"], "open": h["gap_free"]}


def test_curves_mark_the_test_values_and_the_run_peak(small_result, linear_result):
    from icewall.post.curves import plot_curves

    fig = plot_curves([small_result, linear_result])
    ax = fig.axes[0]
    levels = [ln.get_ydata()[0] for ln in ax.lines if ln.get_linestyle() == "--"]
    assert levels == [pytest.approx(4.91)]  # CF-4 test peak, w in MPa (Table 5.1)
    residual = [ln for ln in ax.lines if ln.get_linestyle() == ":"]
    assert np.allclose(residual[0].get_ydata(), 2.50) and np.allclose(residual[0].get_xdata(),
                                                                      [20.0, 40.0])
    with open_result(small_result) as r:
        peak = r.history["load"].max()
    peaks = [ln.get_ydata()[0] for ln in marker_lines(fig, "o")]
    assert peak in peaks
    assert ax.get_xlabel() == "control deflection d (mm)" and ax.get_ylabel() == "w (MPa)"


def test_cli_plot_writes_png_and_svg(small_result, tmp_path):
    result = CliRunner().invoke(main, ["plot", small_result, "-k", "curves,interface",
                                       "--at", "peak,8", "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    pngs, svgs = sorted(tmp_path.glob("*.png")), sorted(tmp_path.glob("*.svg"))
    assert [p.stem for p in pngs] == [p.stem for p in svgs] == [
        "cf4_small_interface_8mm", "cf4_small_interface_peak", "curves"]
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    assert all(b"<svg" in p.read_bytes()[:2000] for p in svgs)


def test_missing_state_fields_is_a_one_line_error(linear_result, tmp_path):
    result = CliRunner().invoke(main, ["plot", linear_result, "-k", "cracks", "--at", "final",
                                       "-o", str(tmp_path)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "concrete_flags" in lines[0] and "outputs.fields" in lines[0] and "state" in lines[0]


def test_deflection_outside_the_run_is_a_clean_error(small_result):
    with open_result(small_result) as r, pytest.raises(Exception, match="no stored step near"):
        step_at(r, 40.0)
