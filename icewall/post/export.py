"""ParaView export: a VTU series (one .vtu per stored step, written by meshio) and the .pvd
collection that ParaView opens as one time series, of the mesh, nodal and cell fields of a run.

Per stored step (time = control deflection in mm where it increases over the stored steps,
else the step number):

* point data ``displacement`` (mm, z = 0 so ParaView's "Warp By Vector" works) and, at both
  nodes of every steel-concrete pair, ``interface_state`` (0 stick, 1 slip, 2 open; -1 at other
  nodes), ``interface_gap_N`` and ``interface_gap_T`` (mm; 0 at other nodes);
* cell data, Gauss-point fields averaged over the cell's Gauss points (plain mean) and named
  ``<field>_<component>_cellmean``: stress (MPa) and strain in xx, yy, zz, xy,
  equivalent_plastic_strain; concrete flags as the fraction of the cell's Gauss points
  ``cracked_in_plane_fraction``, ``cracked_out_of_plane_fraction``, ``crushed_fraction``.
  Orthotropy angles are not averaged (not exported); ``region`` is the region tag.

``RUN_paraview.pvd`` lists ``RUN_paraview/step_NNNNN.vtu``. (Not meshio's XDMF time series:
its writer puts the heavy-data .h5 in the working directory under the .xdmf's stem, where it
could overwrite a result file of the same name.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from icewall.errors import ResultError
from icewall.mesh.convert import meshio_name, to_meshio
from icewall.results.reader import FieldMissing, open_result
from icewall.safe_write import (
    MARK,
    PVD,
    VTU,
    check_replaceable,
    library_output,
    own_directory,
    write_text,
)

COMPONENTS = {"stress": ("xx", "yy", "zz", "xy"), "strain": ("xx", "yy", "zz", "xy")}
FLAG_GROUPS = {"cracked_in_plane_fraction": (0, 1), "cracked_out_of_plane_fraction": (2,),
               "crushed_fraction": (3, 4, 5)}
SKIPPED = ("orthotropy_angle",)


def cell_fields(name: str, field: np.ndarray) -> dict[str, np.ndarray]:
    """Cell data (n_el,) named as in the module docstring of one Gauss field (n_el, nq, k)."""
    if name == "concrete_flags":
        on = np.asarray(field) != 0
        return {key: on[..., list(cols)].any(axis=-1).mean(axis=1)
                for key, cols in FLAG_GROUPS.items()}
    if name in SKIPPED:
        return {}
    mean = np.asarray(field, dtype=float).mean(axis=1)
    names = COMPONENTS.get(name, tuple(str(i) for i in range(mean.shape[1])))
    if mean.shape[1] == 1:
        return {f"{name}_cellmean": mean[:, 0]}
    return {f"{name}_{c}_cellmean": mean[:, i] for i, c in enumerate(names)}


def _interface_data(result, step: int, n_nodes: int) -> dict[str, np.ndarray]:
    pairs = result.mesh.interface_pairs
    out: dict[str, np.ndarray] = {}
    for name, fill in (("state", -1.0), ("gap_N", 0.0), ("gap_T", 0.0)):
        try:
            values = result.array(step, f"interface/{name}")
        except FieldMissing:  # (a damaged one is an error)
            continue
        data = np.full(n_nodes, fill)
        data[pairs[:, 0]] = values
        data[pairs[:, 1]] = values
        out[f"interface_{name}"] = data
    return out


def default_output(result_path: str | Path) -> Path:
    """RUN.h5 -> RUN_paraview.pvd beside it."""
    path = Path(result_path)
    stem = path.name.removesuffix(".partial").removesuffix(".h5")
    return path.with_name(f"{stem}_paraview.pvd")


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection file: (time, relative .vtu path) per step (safe_write)."""
    rows = "\n".join(f'    <DataSet timestep="{t:.17g}" part="0" file="{f}"/>' for t, f in entries)
    write_text(path, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
               f"<!-- written by {MARK} -->\n"
               f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n", PVD)


def export_vtu_series(result_path: str | Path, out: str | Path | None = None,
                      warn=None) -> tuple[Path, str]:
    """Write the .pvd and its .vtu files of a result file; returns (pvd path, time meaning).
    `warn(text)` is told of steps the stored deck says have fields that the file lacks."""
    import meshio

    out = Path(out) if out is not None else default_output(result_path)
    if out.suffix != ".pvd":
        raise ResultError(f"export writes a .pvd collection (with a folder of .vtu), not {out}")
    folder = out.with_suffix("")
    check_replaceable(out, PVD)  # refused before anything is written
    with open_result(result_path) as r:  # a bad result file leaves no folder behind
        mesh, h = r.mesh, r.history
        if not r.steps:
            raise ResultError(f"{result_path}: no step stores fields; nothing to export")
        missing = r.missing_field_steps()
        if missing and warn is not None:
            warn(f"{result_path}: step(s) {', '.join(map(str, missing[:10]))} should store "
                 f"fields but the file lacks them (damaged?); exported the {len(r.steps)} "
                 "stored")
        own_directory(folder, "folder of .vtu files")
        row = {int(s): i for i, s in enumerate(h["step"])}
        defl = np.array([h["control_displacement"][row[s]] for s in r.steps])
        by_deflection = bool(np.all(np.diff(defl) > 0))
        times = defl if by_deflection else np.array(r.steps, dtype=float)
        points = np.column_stack([mesh.points, np.zeros(mesh.n_nodes)])
        cells = [(meshio_name(mesh.cell_type), to_meshio(mesh.cell_type, mesh.cells))]
        entries = []
        for step, t in zip(r.steps, times, strict=True):
            point_data = _interface_data(r, step, mesh.n_nodes)
            try:
                u = r.displacement(step)
                point_data["displacement"] = np.column_stack([u, np.zeros(len(u))])
            except FieldMissing:  # (a damaged one is an error)
                pass
            cell_data = {"region": [mesh.cell_region.astype(np.int32)]}
            for name in r.gauss_fields(step):
                for key, values in cell_fields(name, r.gauss(step, name)).items():
                    cell_data[key] = [values]
            vtu = folder / f"step_{step:05d}.vtu"
            with library_output(vtu, VTU) as name:
                meshio.write(name, meshio.Mesh(points, cells, point_data=point_data,
                                               cell_data=cell_data), file_format="vtu")
            entries.append((float(t), f"{folder.name}/{vtu.name}"))
    write_pvd(out, entries)
    return out, "control deflection (mm)" if by_deflection else "step number"
