"""Write a Mesh with meshio (gmsh .msh, .vtu, .xdmf) and describe it for people."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from icewall.fem.kinematics import gauss_point_spacing
from icewall.mesh.convert import meshio_name, to_meshio
from icewall.mesh.mesh import Mesh

FORMATS = {"msh": ("gmsh", ".msh"), "vtu": ("vtu", ".vtu"), "xdmf": ("xdmf", ".xdmf")}


def to_meshio_mesh(mesh: Mesh):
    import meshio

    points = np.column_stack([mesh.points, np.zeros(mesh.n_nodes)])
    cells = [(meshio_name(mesh.cell_type), to_meshio(mesh.cell_type, mesh.cells))]
    region = mesh.cell_region.astype(np.int32) + 1
    return meshio.Mesh(points, cells, cell_data={
        "region": [region], "gmsh:physical": [region], "gmsh:geometrical": [region]},
        field_data={r.name: np.array([r.tag + 1, 2]) for r in mesh.regions})


def write_mesh(mesh: Mesh, stem: str | Path, formats: list[str]) -> list[Path]:
    """Write `stem`.msh/.vtu/.xdmf; returns the paths written."""
    import meshio

    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise ValueError(f"unknown mesh format(s) {unknown}; choose from {list(FORMATS)}")
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    m = to_meshio_mesh(mesh)
    written = []
    for fmt in formats:
        file_format, suffix = FORMATS[fmt]
        path = stem.with_suffix(suffix)
        kwargs = {"binary": False} if fmt == "msh" else {}
        meshio.write(path, m, file_format=file_format, **kwargs)
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
