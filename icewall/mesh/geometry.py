"""Mesh a block layout with gmsh: one structured (transfinite, recombined) patch per block."""

from __future__ import annotations

import numpy as np

from icewall.errors import MeshError, ResultError
from icewall.mesh.convert import from_gmsh, gmsh_type, orient_counter_clockwise
from icewall.mesh.layout import Layout
from icewall.safe_write import MSH, library_output


def mesh_layout(layout: Layout, cell_type: str, model_name: str = "wall",
                msh_path: str | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                      list[str]]:
    """Mesh every block; returns (points (n,2), cells, cell_region_index, region_names).

    Nodes are shared between blocks (conforming); interfaces are split afterwards.
    If `msh_path` is given, gmsh also writes its own (conforming) mesh there.
    """
    import signal
    import threading

    import gmsh

    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    initialized_here = not gmsh.isInitialized()
    if initialized_here:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(model_name)
        region_names = sorted({b.region for b in layout.blocks})
        surfaces = _build_geometry(gmsh, layout, region_names)
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
        gmsh.model.mesh.generate(2)
        if cell_type == "quad8":
            gmsh.model.mesh.setOrder(2)
        if msh_path is not None:  # through safe_write: no link followed, no file replaced
            with library_output(msh_path, MSH) as name:
                gmsh.write(name)
        return _extract(gmsh, cell_type, surfaces, region_names)
    except (MeshError, ResultError):
        raise
    except Exception as exc:  # gmsh raises plain Exception
        raise MeshError(f"gmsh failed: {exc}") from exc
    finally:
        if initialized_here:
            gmsh.finalize()
        else:
            gmsh.model.remove()
        if threading.current_thread() is threading.main_thread():
            for signum, handler in handlers.items():  # gmsh installs its own handlers
                if handler is not None:
                    signal.signal(signum, handler)


def _build_geometry(gmsh, layout: Layout, region_names: list[str]) -> dict[int, str]:
    geo = gmsh.model.geo
    xs, ys = layout.x_lines, layout.y_lines
    point_tags: dict[tuple[int, int], int] = {}
    h_tags: dict[tuple[int, int], int] = {}  # (ix, iy): line from (ix,iy) to (ix+1,iy)
    v_tags: dict[tuple[int, int], int] = {}  # (ix, iy): line from (ix,iy) to (ix,iy+1)

    def point(i: int, j: int) -> int:
        if (i, j) not in point_tags:
            point_tags[(i, j)] = geo.addPoint(float(xs[i]), float(ys[j]), 0.0)
        return point_tags[(i, j)]

    def h_line(i: int, j: int) -> int:
        if (i, j) not in h_tags:
            h_tags[(i, j)] = geo.addLine(point(i, j), point(i + 1, j))
        return h_tags[(i, j)]

    def v_line(i: int, j: int) -> int:
        if (i, j) not in v_tags:
            v_tags[(i, j)] = geo.addLine(point(i, j), point(i, j + 1))
        return v_tags[(i, j)]

    surface_region: dict[int, str] = {}
    for block in layout.blocks:
        i, j = block.ix, block.iy
        loop = geo.addCurveLoop([h_line(i, j), v_line(i + 1, j), -h_line(i, j + 1), -v_line(i, j)])
        surface_region[geo.addPlaneSurface([loop])] = block.region
    geo.synchronize()
    mesh = gmsh.model.mesh
    for (i, _), tag in h_tags.items():
        mesh.setTransfiniteCurve(tag, int(layout.x_divisions[i]) + 1)
    for (_, j), tag in v_tags.items():
        mesh.setTransfiniteCurve(tag, int(layout.y_divisions[j]) + 1)
    for tag in surface_region:
        mesh.setTransfiniteSurface(tag)
        mesh.setRecombine(2, tag)
    for name in region_names:
        tags = [t for t, r in surface_region.items() if r == name]
        group = gmsh.model.addPhysicalGroup(2, tags)
        gmsh.model.setPhysicalName(2, group, name)
    return surface_region


def _extract(gmsh, cell_type: str, surfaces: dict[int, str], region_names: list[str]):
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(node_tags)
    node_tags = node_tags[order]
    points = coords.reshape(-1, 3)[order, :2]
    etype = gmsh_type(cell_type)
    cells, regions = [], []
    for tag, name in sorted(surfaces.items()):
        types, _, enodes = gmsh.model.mesh.getElements(2, tag)
        if list(types) != [etype]:
            raise MeshError(f"block of {name} was not meshed with {cell_type} only "
                            f"(gmsh types {list(types)})")
        conn = np.asarray(enodes[0], dtype=np.int64).reshape(-1, _arity(cell_type))
        cells.append(conn)
        regions.append(np.full(len(conn), region_names.index(name)))
    conn = np.concatenate(cells)
    index = np.searchsorted(node_tags, conn)
    used = np.unique(index)
    renumber = np.full(len(node_tags), -1)
    renumber[used] = np.arange(len(used))
    cells_icewall = from_gmsh(cell_type, renumber[index])
    points = points[used]
    cells_icewall = orient_counter_clockwise(points, cells_icewall, cell_type)
    return points, cells_icewall, np.concatenate(regions), region_names


def _arity(cell_type: str) -> int:
    return 8 if cell_type == "quad8" else 4
