"""Off-screen PNG of von Mises stress (or another field of FIELDS, e.g. the contact pressure) on the
deformed shape (pyvista + matplotlib), 2-D and 3-D.

Input: a case's `fields.npz`, written by the solver (rank 0, gathered P1 data):
  points        (N, 3) reference coordinates of the mesh nodes (z = 0 in 2-D)
  cells         (M, k) node indices per cell (k = 3 triangles, 4 tetrahedra)
  cell_type     "triangle" or "tetra"
  displacement  (N, 3) nodal displacement, zero-padded in 2-D
  von_mises     (N,) nodal or (M,) cellwise von Mises stress (nodal when N == M)
  contact_pressure (N,) optional, nodal (fields.npz has it, with the other contact fields)
  rigid_outline (P, 3) optional polyline of the rigid body in its final pose
  named_point_names (K,), named_point_coords (K, 3)  optional points a zoom may name

Each view has its own colour bar, beside it (outside the geometry), from the field's minimum
to its `percentile` (99th by default) weighted by area (volume in 3-D): the value exceeded
on 1 % of the body, or of the zoomed region (cells whose centroid lies within the zoom
radius of its centre, in every coordinate). Sharp rigid corners make a stress singularity
whose peak would otherwise paint everything else in the lowest colour. Values above the
range take the top colour (the bar's arrow); the title states the true maximum and where it
is (reference coordinates, and the nearest named point). pyvista draws each view without
annotations (2-D without lighting, so the colours are the bar's); matplotlib lays them out.
"""
import os

import numpy as np

CELL_TYPES = {"triangle": 5, "tetra": 10}  # VTK_TRIANGLE, VTK_TETRA
PERCENTILE = 99.0
CMAP = "jet"
FIELDS = {"von_mises": "von Mises stress", "contact_pressure": "contact pressure"}
"""The fields a picture may show (MPa), by their name in the fields file."""


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
    if not r > 0:
        raise ValueError(f"zoom {list(zoom)}: the radius (its last value, mm) must be > 0")
    return np.array(list(centre) + [0.0] * (3 - len(centre))), float(r)


def peak(fields: dict, field: str = "von_mises") -> dict:
    """The largest value of `field` (MPa), where it is (reference coordinates of the node or cell
    centroid, mm) and the nearest named point with its distance (mm), if the file names points."""
    values, points = fields[field], fields["points"]
    index = int(np.argmax(values))
    where = points[index] if len(values) == len(points) else points[fields["cells"][index]].mean(axis=0)
    out = {"value": float(values[index]), "at": where, "near": None, "distance": None}
    names = [str(name) for name in fields.get("named_point_names", [])]
    if names:
        distances = np.linalg.norm(fields["named_point_coords"] - where, axis=1)
        out["near"], out["distance"] = names[int(np.argmin(distances))], float(distances.min())
    return out


def measures(fields: dict, field: str = "von_mises") -> np.ndarray:
    """Area (triangles, mm^2) or volume (tetrahedra, mm^3) of each value's share of the body:
    the cell's own for cellwise values, a third (a quarter) of each adjacent cell's for nodal values."""
    points, cells = fields["points"], fields["cells"]
    edges = points[cells[:, 1:]] - points[cells[:, :1]]
    if cells.shape[1] == 3:
        size = 0.5 * np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    else:
        size = np.abs(np.linalg.det(edges)) / 6
    if len(fields[field]) == len(cells) and len(cells) != len(points):
        return size
    nodal = np.zeros(len(points))
    np.add.at(nodal, cells.ravel(), np.repeat(size / cells.shape[1], cells.shape[1]))
    return nodal


def weighted_percentile(values: np.ndarray, weights: np.ndarray, percentile: float) -> float:
    """The smallest value v such that the values <= v carry at least `percentile` % of the weight."""
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cumulative, percentile / 100 * cumulative[-1])])


def colour_range(fields: dict, percentile: float, region=None, field: str = "von_mises") -> tuple[float, float]:
    """(min, weighted percentile) of `field` over the body, or over a zoom region (centre, radius)."""
    values, weights = fields[field], measures(fields, field)
    if region is not None:
        centre, radius = region
        where = fields["points"] if len(values) == len(fields["points"]) else \
            fields["points"][fields["cells"]].mean(axis=1)
        inside = np.abs(where - centre).max(axis=1) <= radius
        if inside.any():
            values, weights = values[inside], weights[inside]
    low, high = float(values.min()), weighted_percentile(values, weights, percentile)
    return (low, high) if high > low else (low, max(float(values.max()), low + 1e-12))


def _trim(image: np.ndarray, margin: int = 8) -> np.ndarray:
    """The screenshot without its uniform background border (all but `margin` pixels of it)."""
    rows, columns = np.nonzero((image != image[0, 0]).any(axis=2))
    if not len(rows):
        return image
    return image[max(rows.min() - margin, 0): rows.max() + margin + 1,
                 max(columns.min() - margin, 0): columns.max() + margin + 1]


def _quiet_offscreen() -> None:
    """Off-screen rendering without a display: pick VTK's OSMesa window (libosmesa6) instead of
    letting VTK try X first and warn "bad X server connection. DISPLAY=" on every render."""
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")


def render(fields_npz_path, png_path, zoom=None, scale=1.0, zoom_radius=0.0, size=(1600, 700),
           percentile=PERCENTILE, field="von_mises") -> dict:
    """Write the PNG of `field` (a key of FIELDS; whole body, beside it the zoom, when given). Returns
    {'ranges': [(min, max) of each view's colour map as rendered], 'peak': peak(fields, field)}."""
    if field not in FIELDS:
        raise ValueError(f"field {field!r}: expected one of {', '.join(FIELDS)}")
    _quiet_offscreen()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pyvista

    fields = load(fields_npz_path)
    if field not in fields:
        raise ValueError(f"{fields_npz_path}: no {field} (a fields.npz written without contact fields)")
    points, cells = fields["points"], fields["cells"]
    flat = np.hstack([np.full((len(cells), 1), cells.shape[1]), cells]).ravel()
    grid = pyvista.UnstructuredGrid(flat, np.full(len(cells), CELL_TYPES[str(fields["cell_type"])]),
                                    points + scale * fields["displacement"])
    values, name = fields[field], FIELDS[field]
    (grid.point_data if len(values) == len(points) else grid.cell_data)[name] = values
    plane = bool(np.allclose(points[:, 2], 0))
    views = [None] if zoom is None else [None, zoom_box(fields, zoom, zoom_radius)]
    images, ranges = [], []
    for view in views:
        plotter = pyvista.Plotter(off_screen=True, window_size=(size[0] // len(views), size[1]))
        actor = plotter.add_mesh(grid, scalars=name, clim=colour_range(fields, percentile, view, field), cmap=CMAP,
                                 show_edges=view is not None, show_scalar_bar=False, lighting=not plane)
        if "rigid_outline" in fields and len(fields["rigid_outline"]) > 1:  # 3-D cylinders have none
            plotter.add_mesh(pyvista.lines_from_points(fields["rigid_outline"]), color="black", line_width=3)
        _place_camera(plotter, grid, plane, view)
        image = plotter.screenshot(return_img=True)
        images.append(_trim(image) if view is None else image)  # the zoom is framed by its camera
        ranges.append(tuple(float(v) for v in actor.mapper.lookup_table.scalar_range))
        plotter.close()

    top = peak(fields, field)
    dpi = 100
    aspects = [image.shape[1] / image.shape[0] for image in images]
    bars, titles = 1.1 * len(views), 1.1  # inches
    panel = min(size[1] / dpi - titles, (size[0] / dpi - bars) / sum(aspects))  # height of the views
    figure = plt.figure(figsize=(panel * sum(aspects) + bars, panel + titles), dpi=dpi, layout="constrained")
    axes = figure.subplots(1, len(views), squeeze=False, gridspec_kw={"width_ratios": aspects})[0]
    for ax, image, view, limits in zip(axes, images, views, ranges):
        ax.imshow(image)
        ax.set_axis_off()
        ax.set_title("whole body" if view is None else
                     f"{zoom if isinstance(zoom, str) else 'zoom'}, {2 * view[1]:.3g} mm wide", fontsize=11)
        mappable = matplotlib.cm.ScalarMappable(matplotlib.colors.Normalize(*limits), CMAP)
        bar = figure.colorbar(mappable, ax=ax, extend="max", shrink=0.9, aspect=30, pad=0.02)
        bar.set_label(f"{name} (MPa)", fontsize=10)
    where = ", ".join(f"{c:.4g}" for c in top["at"][: 2 if plane else 3])
    near = f", {top['distance']:.2g} mm from {top['near']}" if top["near"] else ""
    figure.suptitle(f"{name}, displacements x {scale:g}: max {top['value']:.4g} MPa at ({where}) mm{near}\n"
                    f"each colour bar: minimum to the {percentile:g}th percentile (by area) of its view; "
                    "above: top colour", fontsize=11)
    figure.savefig(png_path, dpi=dpi)
    plt.close(figure)
    return {"ranges": ranges, "peak": top}


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
