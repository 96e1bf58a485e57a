"""Write a Mesh with meshio (gmsh .msh, .vtu, .xdmf) and describe it for people."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from icewall.fem.kinematics import gauss_point_spacing
from icewall.mesh.convert import EDGE_TABLE, meshio_name, to_meshio
from icewall.mesh.mesh import Mesh
from icewall.safe_write import HDF5_MAGIC, MSH, VTU, XDMF, Kind, library_output

FORMATS = {"msh": ("gmsh22", ".msh"), "vtu": ("vtu", ".vtu"), "xdmf": ("xdmf", ".xdmf")}
KINDS = {"msh": MSH, "vtu": VTU, "xdmf": XDMF}  # how an earlier one is recognised (safe_write)


def _is_xdmf_data(path: str) -> bool:
    """Whether `path` is the heavy-data HDF5 file meshio writes beside an .xdmf (datasets
    data0, data1, ... and nothing else; never an icewall result)."""
    import h5py

    try:
        with h5py.File(path, "r", locking=False) as f:
            return bool(len(f)) and not f.attrs and all(
                k.startswith("data") and k[4:].isdigit() for k in f)
    except Exception:  # noqa: BLE001 - unreadable: not recognised, so not replaced
        return False


XDMF_DATA = Kind("XDMF heavy-data file", starts=HDF5_MAGIC, check=_is_xdmf_data)


def to_meshio_mesh(mesh: Mesh, gmsh_tags: bool = False, sets: bool = True):
    """A meshio Mesh with one physical group per region, edge set (lines) and node set.

    The group tag is cell data "set" (or gmsh:physical/gmsh:geometrical for .msh files);
    `sets=False` keeps only the elements (XDMF readers handle one topology best).
    """
    import meshio

    points = np.column_stack([mesh.points, np.zeros(mesh.n_nodes)])
    blocks = [(meshio_name(mesh.cell_type), to_meshio(mesh.cell_type, mesh.cells),
               mesh.cell_region.astype(np.int32) + 1)]
    field_data = {r.name: np.array([r.tag + 1, 2]) for r in mesh.regions}
    tag = len(mesh.regions)
    for name, edges in sorted(mesh.edge_sets.items()) if sets else ():
        tag += 1
        blocks.append((EDGE_TABLE[edges.shape[1]][1], edges, np.full(len(edges), tag)))
        field_data[name] = np.array([tag, 1])
    for name, nodes in sorted(mesh.node_sets.items()) if sets else ():
        tag += 1
        blocks.append(("vertex", nodes.reshape(-1, 1), np.full(len(nodes), tag)))
        field_data[name] = np.array([tag, 0])
    tags = [b[2].astype(np.int32) for b in blocks]
    return meshio.Mesh(points, [(b[0], b[1]) for b in blocks],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags}
                       if gmsh_tags else {"set": tags},
                       field_data=field_data)


def write_mesh(mesh: Mesh, stem: str | Path, formats: list[str]) -> list[Path]:
    """Write `stem`.msh/.vtu/.xdmf; returns the paths written."""
    import meshio

    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise ValueError(f"unknown mesh format(s) {unknown}; choose from {list(FORMATS)}")
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    written = []
    for fmt in formats:
        file_format, suffix = FORMATS[fmt]
        path = stem.with_suffix(suffix)
        kwargs = {"binary": False} if fmt == "msh" else {}
        m = to_meshio_mesh(mesh, gmsh_tags=fmt == "msh", sets=fmt != "xdmf")
        # meshio writes the heavy data of an .xdmf beside it as STEM.h5
        companions = {path.with_suffix(".h5").name: XDMF_DATA} if fmt == "xdmf" else {}
        with library_output(path, KINDS[fmt], companions) as name:
            meshio.write(name, m, file_format=file_format, **kwargs)
        written.append(path)
    return written


def mesh_report(mesh: Mesh, n_gauss: int) -> str:
    """Node/element counts and the Gauss-point spacing h_c (eq. 4.3) per region."""
    spacing = gauss_point_spacing(mesh.points, mesh.cells, n_gauss)
    lines = [f"{mesh.n_nodes} nodes, {mesh.n_cells} {mesh.cell_type} elements, "
             f"{len(mesh.interface_pairs)} interface node pairs "
             f"({int(mesh.interface_corner.sum())} at core corners)",
             f"{'region':<18}{'kind':<10}{'elements':>9}{'h_c min':>10}{'h_c mean':>10}"
             f"{'h_c max':>10}  (mm, {n_gauss}x{n_gauss} Gauss)"]
    for region in sorted(mesh.regions, key=lambda r: r.tag):
        sel = mesh.cell_region == region.tag
        h = spacing[sel]
        lines.append(f"{region.name:<18}{region.kind:<10}{sel.sum():>9d}{h.min():>10.2f}"
                     f"{h.mean():>10.2f}{h.max():>10.2f}")
    return "\n".join(lines)
