"""Off-screen PNG of von Mises stress on the deformed shape (pyvista), 2-D and 3-D.

Input: a case's `fields.npz`, written by the solver (rank 0, gathered P1 data):
  points        (N, 3) reference coordinates of the mesh nodes (z = 0 in 2-D)
  cells         (M, k) node indices per cell (k = 3 triangles, 4 tetrahedra)
  cell_type     "triangle" or "tetra"
  displacement  (N, 3) nodal displacement, zero-padded in 2-D
  von_mises     (N,) nodal or (M,) cellwise von Mises stress (nodal when N == M)
  rigid_outline (P, 3) optional polyline of the rigid body in its final pose
  named_point_names (K,), named_point_coords (K, 3)  optional points a zoom may name
The colour bar spans exactly the field's min..max.
"""
import os

import numpy as np

CELL_TYPES = {"triangle": 5, "tetra": 10}  # VTK_TRIANGLE, VTK_TETRA


def load(path) -> dict:
    """The arrays of a fields file, checked for shape."""
    with np.load(path) as data:
        fields = {name: data[name] for name in data.files}
    cell_type = str(fields["cell_type"])
    if cell_type not in CELL_TYPES:
        raise ValueError(f"{path}: cell_type {cell_type!r}: expected 'triangle' or 'tetra'")
    n, m = len(fields["points"]), len(fields["cells"])
    if fields["displacement"].shape != (n, 3) or len(fields["von_mises"]) not in (n, m):
        raise ValueError(f"{path}: displacement must be ({n}, 3) and von_mises ({n},) or ({m},)")
    return fields


def zoom_box(fields: dict, zoom, radius: float = 0.0):
    """(centre (3,), radius) of a zoom: a named point (radius default 1/8 of the model size) or [x, y(, z), r]."""
    if isinstance(zoom, str):
        names = [str(name) for name in fields.get("named_point_names", [])]
        if zoom not in names:
            raise ValueError(f"zoom {zoom!r}: not a named point of the fields file (has: {', '.join(names)})")
        centre = fields["named_point_coords"][names.index(zoom)]
        size = np.ptp(fields["points"], axis=0).max()
        return np.asarray(centre, float), radius or size / 8
    *centre, r = zoom
    return np.array(list(centre) + [0.0] * (3 - len(centre))), float(r)


def render(fields_npz_path, png_path, zoom=None, scale=1.0, zoom_radius=0.0, size=(1600, 700)) -> dict:
    """Write the PNG (whole body; beside it the zoom, when given); returns {'range': (min, max)}."""
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista

    fields = load(fields_npz_path)
    points, cells = fields["points"], fields["cells"]
    flat = np.hstack([np.full((len(cells), 1), cells.shape[1]), cells]).ravel()
    grid = pyvista.UnstructuredGrid(flat, np.full(len(cells), CELL_TYPES[str(fields["cell_type"])]),
                                    points + scale * fields["displacement"])
    von_mises = fields["von_mises"]
    (grid.point_data if len(von_mises) == len(points) else grid.cell_data)["von Mises"] = von_mises
    clim = (float(von_mises.min()), float(von_mises.max()))
    plane = bool(np.allclose(points[:, 2], 0))
    views = [None] if zoom is None else [None, zoom_box(fields, zoom, zoom_radius)]
    plotter = pyvista.Plotter(off_screen=True, shape=(1, len(views)), window_size=size)
    ranges = []
    for column, view in enumerate(views):
        plotter.subplot(0, column)
        actor = plotter.add_mesh(grid, scalars="von Mises", clim=clim, cmap="jet", show_edges=view is not None,
                                 scalar_bar_args={"title": "MPa", "vertical": True, "fmt": "%.4g",
                                                  "position_x": 0.85, "position_y": 0.1, "width": 0.08})
        ranges.append(tuple(actor.mapper.lookup_table.scalar_range))
        if "rigid_outline" in fields and len(fields["rigid_outline"]) > 1:  # 3-D cylinders have none
            plotter.add_mesh(pyvista.lines_from_points(fields["rigid_outline"]), color="black", line_width=3)
        _place_camera(plotter, grid, plane, view)
        plotter.add_text("von Mises stress, " + ("contact zone" if view is not None else "deformed shape"),
                         font_size=10)
    plotter.screenshot(str(png_path))
    plotter.close()
    assert all(r == ranges[0] for r in ranges)
    return {"range": ranges[0]}


def _place_camera(plotter, grid, plane: bool, view) -> None:
    if plane:
        plotter.view_xy()
        plotter.enable_parallel_projection()
    else:
        plotter.view_isometric()
    if view is None:
        plotter.reset_camera()
        return
    centre, radius = view
    camera = plotter.camera
    direction = np.array(camera.position) - np.array(camera.focal_point)
    direction /= np.linalg.norm(direction)
    camera.focal_point = tuple(centre)
    camera.position = tuple(centre + direction * radius * 4)
    camera.parallel_scale = radius
    if not plane:
        camera.view_angle = 2 * np.degrees(np.arctan(1 / 4))
    plotter.reset_camera_clipping_range()
