"""`femcontact animate CASE_DIR`: a film of a run, from its ParaView time series.

One picture per frame of `fields.xdmf` (a run with `outputs.fields = true`): on the left the
deformable body, displaced (x `scale`) and coloured by von Mises stress, with the rigid body
(`rigid.xdmf`, its outline in 2-D, its surface in 3-D) displaced with it; on the right the forces
of `history.csv` against time, a marker at the frame's time. Written as CASE_DIR/animation.mp4
(H.264 through ffmpeg) and CASE_DIR/animation.gif, each written whole or not at all. The colour range is fixed for the whole film:
from 0 to the 99th percentile of von Mises over all frames' cells (a sharp corner's singular
peak would otherwise leave the rest in the lowest colour); higher values take the top colour.
2-D pictures are drawn by matplotlib, 3-D ones rendered off-screen by pyvista.
"""
import os
import shutil
from pathlib import Path

import numpy as np

from femcontact.errors import InputError
from femcontact.outputs.history import read_history

PERCENTILE = 99.0
CMAP = "jet"


def add_arguments(parser):
    parser.add_argument("case", help="case directory of a run with outputs.fields = true")
    parser.add_argument("--scale", type=float, default=1.0, help="displacement magnification (default 1)")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per second (default 10)")
    parser.add_argument("--force", action="append", default=[], metavar="COLUMN",
                        help="history column drawn against time (repeatable; default: the contact forces, "
                             "or the reactions, and the applied forces)")


def command(args) -> int:
    paths = animate(args.case, scale=args.scale, fps=args.fps, forces=args.force or None)
    for path in paths:
        print(f"animation: {path}")
    return 0


def read_series(path: Path) -> tuple:
    """(points N x 3, cells M x k, [(time, point data, cell data)]) of an XDMF time series."""
    import meshio

    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        frames = []
        for k in range(reader.num_steps):
            time, point_data, cell_data = reader.read_data(k)
            frames.append((time, point_data, {name: values[0] for name, values in cell_data.items()}))
    return points, cells[0].data, frames


def force_columns(history: dict) -> list[str]:
    """The forces worth watching: each contact zone's resultant, else each support's reaction;
    and the applied force components that are not zero throughout."""
    contact = [name for name in history if name.startswith("contact_") and name.endswith("_force")]
    reactions = [name for name in history if name.startswith("reaction_") and name.count("_") == 2]
    applied = [name for name in history if name.startswith("applied_F") and np.nanmax(np.abs(history[name])) > 0]
    return (contact or reactions) + applied


def animate(case_dir, scale: float = 1.0, fps: float = 10.0, forces=None) -> list[Path]:
    """Write CASE_DIR/animation.mp4 and animation.gif; returns their paths."""
    case_dir = Path(case_dir)
    for name in ("fields.xdmf", "history.csv"):
        if not (case_dir / name).exists():
            raise InputError(f"{case_dir / name}: missing; run the scene with --set outputs.fields=true")
    if shutil.which("ffmpeg") is None:
        raise InputError("ffmpeg: not found; install Debian's ffmpeg (`make setup` does)")
    points, cells, frames = read_series(case_dir / "fields.xdmf")
    if not frames:
        raise InputError(f"{case_dir / 'fields.xdmf'}: no frame written yet")
    rigid = read_series(case_dir / "rigid.xdmf") if (case_dir / "rigid.xdmf").exists() else None
    history = read_history(case_dir / "history.csv")
    forces = forces or force_columns(history)
    numeric = [name for name, values in history.items() if values.dtype != object]
    unknown = [name for name in forces if name not in numeric]
    if unknown:
        raise InputError(f"--force {unknown[0]}: not a column of history.csv (numeric columns: {', '.join(numeric)})")
    stress = np.concatenate([frame[2]["von_mises"].ravel() for frame in frames])
    limits = (0.0, max(float(np.percentile(stress, PERCENTILE)), 1e-12))
    draw = _Plane(points, cells, rigid) if np.allclose(points[:, 2], 0) else _Solid(points, cells, rigid)
    return _write(case_dir, frames, rigid, history, forces, draw, limits, scale, fps)


def _write(case_dir, frames, rigid, history, forces, draw, limits, scale, fps) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    figure, (body, trace) = plt.subplots(1, 2, figsize=(12.8, 5.6), dpi=100, layout="constrained",
                                         gridspec_kw={"width_ratios": [1.25, 1]})
    mappable = matplotlib.cm.ScalarMappable(matplotlib.colors.Normalize(*limits), CMAP)
    figure.colorbar(mappable, ax=body, extend="max", shrink=0.85, label="von Mises (MPa)")
    time = history.get("time", np.arange(len(next(iter(history.values()), []))))
    for name in forces:
        trace.plot(time, history[name], label=name)
    trace.set(xlabel="time (s)", ylabel="force (N)", title="forces (history.csv)")
    trace.grid(True, alpha=0.3)
    trace.legend(fontsize=8)
    marker = trace.axvline(frames[0][0], color="k", linewidth=1)
    title = figure.suptitle("")

    def frame(k: int):
        t, point_data, cell_data = frames[k]
        moved = rigid[2][k][1]["displacement"] * scale if rigid is not None else None
        draw(body, point_data["displacement"] * scale, cell_data["von_mises"].ravel(), moved, limits)
        marker.set_xdata([t, t])
        title.set_text(f"{case_dir.name}: t = {t:.4g} s (frame {k + 1}/{len(frames)}), "
                       f"displacements x {scale:g}; max von Mises {cell_data['von_mises'].max():.4g} MPa")
        return []

    film = animation.FuncAnimation(figure, frame, frames=len(frames), blit=False)
    writers = {".mp4": animation.FFMpegWriter(fps=fps, codec="libx264", extra_args=["-pix_fmt", "yuv420p"]),
               ".gif": animation.PillowWriter(fps=fps)}
    paths = []
    for suffix, writer in writers.items():  # each written whole under a temporary name, then renamed
        path = case_dir / f"animation{suffix}"
        temporary = path.with_name(f".animation.{os.getpid()}.tmp{suffix}")
        try:
            film.save(temporary, writer=writer)
            os.replace(temporary, path)
        finally:
            temporary.unlink(missing_ok=True)
        paths.append(path)
    plt.close(figure)
    return paths


class _Plane:
    """2-D: the deformed triangles coloured cell by cell, the rigid outline in black."""

    def __init__(self, points, cells, rigid):
        self.points, self.cells, self.rigid = points[:, :2], cells, rigid
        self.bounds = None

    def __call__(self, axes, displacement, von_mises, rigid_displacement, limits):
        axes.clear()
        x = self.points + displacement[:, :2]
        axes.tripcolor(x[:, 0], x[:, 1], self.cells, facecolors=von_mises, cmap=CMAP, vmin=limits[0],
                       vmax=limits[1], shading="flat")
        if self.rigid is not None:
            placed = self.rigid[0][:, :2] + rigid_displacement[:, :2]
            for a, b in self.rigid[1]:
                axes.plot(*placed[[a, b]].T, color="k", linewidth=2)
        if self.bounds is None:  # the first frame's view, kept: the camera does not follow the bodies
            axes.autoscale()
            self.bounds = axes.get_xlim(), axes.get_ylim()
        axes.set(xlim=self.bounds[0], ylim=self.bounds[1], aspect="equal", xlabel="x (mm)", ylabel="y (mm)")


class _Solid:
    """3-D: the deformed body rendered off-screen by pyvista (isometric view), the rigid surface
    see-through, shown as a picture."""

    def __init__(self, points, cells, rigid):
        from femcontact.outputs.snapshot import _quiet_offscreen

        _quiet_offscreen()
        import pyvista

        self.pyvista, self.rigid = pyvista, rigid
        flat = np.hstack([np.full((len(cells), 1), 4), cells]).ravel()
        self.grid = pyvista.UnstructuredGrid(flat, np.full(len(cells), 10), points.copy())
        self.points = points
        self.camera = None

    def __call__(self, axes, displacement, von_mises, rigid_displacement, limits):
        pyvista = self.pyvista
        self.grid.points = self.points + displacement
        self.grid.cell_data["von Mises"] = von_mises
        plotter = pyvista.Plotter(off_screen=True, window_size=(800, 640))
        plotter.add_mesh(self.grid, scalars="von Mises", clim=limits, cmap=CMAP, show_scalar_bar=False)
        if self.rigid is not None:
            points, triangles, _ = self.rigid
            surface = pyvista.PolyData(points + rigid_displacement,
                                       np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
            plotter.add_mesh(surface, color="grey", opacity=0.4)
        plotter.view_isometric()
        if self.camera is None:
            plotter.reset_camera()
            self.camera = plotter.camera_position
        plotter.camera_position = self.camera
        image = plotter.screenshot(return_img=True)
        plotter.close()
        axes.clear()
        axes.imshow(image)
        axes.set_axis_off()
