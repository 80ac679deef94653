"""ParaView time series (outputs.fields): one frame per converged increment, read back with meshio's
time-series reader; contact fields checked against Coulomb's law and the prescribed motion."""
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest

from femcontact.families import resolve_scene
from femcontact.families.case import run_contact

ROOT = Path(__file__).resolve().parents[2]
MU, PRESS, SLIDE = 0.3, 1000.0, 0.05
NODE_FIELDS = {"displacement", "contact_pressure", "tangential_traction", "contact_status", "slip", "gap"}
CELL_FIELDS = {"von_mises", "stress"}


def read(path: Path) -> tuple:
    """(points, cells, [(time, point data, cell data)]) of an XDMF time series, with meshio."""
    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        frames = [reader.read_data(k) for k in range(reader.num_steps)]
    return points, cells, frames


def friction_block(dim: int, every: int = 1) -> dict:
    """A block pressed by a rigid flat wider than it, dragged by SLIDE (mm), dragged back."""
    press = {"force": [0.0, -PRESS] if dim == 2 else [0.0, 0.0, -PRESS], "load_point": "indenter"}
    held = {"x": "prescribed", "rz": "held"} if dim == 2 else \
        {"x": "prescribed", "y": "held", "rx": "held", "ry": "held", "rz": "held"}
    block = {"width": 20.0, "height": 10.0} if dim == 2 else {"width": 10.0, "height": 5.0, "depth": 10.0}
    mesh = {"contact_size": 0.5, "contact_zone": 9.0, "size_max": 2.0} if dim == 2 else \
        {"contact_size": 2.0, "contact_zone": 4.0, "size_max": 5.0}
    return resolve_scene({
        "name": "friction_block", "dim": dim, "geometry": "block", "rigid": "indenter",
        "effects": ["friction", "plane_strain"] if dim == 2 else ["friction"],
        "block": block, "indenter": {"shape": "flat", "width": 40.0 if dim == 2 else 30.0},
        "materials": {"block": {"E": 200000.0, "nu": 0.3}}, "mesh": mesh, "contact": {"mu": MU},
        "rigid_body": {"dofs": held}, "outputs": {"fields": True, "every": every},
        "steps": [{"name": "press", "increments": 2, **press},
                  {"name": "slide", "increments": 3, **press, "motion": {"x": SLIDE}}],
    })


@pytest.fixture(scope="module")
def block_2d(tmp_path_factory):
    out = tmp_path_factory.mktemp("block_2d")
    run_contact(friction_block(2), out)
    return out


def test_one_frame_per_increment_at_the_scenes_times(block_2d):
    points, cells, frames = read(block_2d / "fields.xdmf")
    assert [t for t, _, _ in frames] == pytest.approx([0.5, 1.0, 4 / 3, 5 / 3, 2.0])
    assert cells[0].type == "triangle" and points.shape[1] == 3
    for _, point_data, cell_data in frames:
        assert set(point_data) == NODE_FIELDS and set(cell_data) == CELL_FIELDS
        assert point_data["displacement"].shape == (len(points), 3)
        assert cell_data["stress"][0].shape == (len(cells[0].data), 9)
    rows = (block_2d / "history.csv").read_text().splitlines()
    assert len(frames) == len(rows) - 1


def test_sliding_nodes_obey_coulomb_and_slip_with_the_flat(block_2d):
    """At the end of the drag every touching node slips with |t_T| = mu p (the 2-D contact terms are
    integrated at the nodes, so the lumped values are the nodal ones), and its slip since the drag
    began is the flat's motion less its own: SLIDE - (u_x now - u_x after the press)."""
    _, _, frames = read(block_2d / "fields.xdmf")
    _, nodal, cellwise = frames[-1]
    touching = nodal["contact_pressure"][:, 0] > 0
    assert touching.sum() >= 20
    assert np.all(nodal["contact_status"][touching, 0] == 2)
    traction = np.linalg.norm(nodal["tangential_traction"][touching], axis=1)
    assert traction == pytest.approx(MU * nodal["contact_pressure"][touching, 0], rel=1e-6)
    moved = nodal["displacement"][:, 0] - frames[1][1]["displacement"][:, 0]  # frame 1: end of the press
    assert nodal["slip"][touching, 0] == pytest.approx(SLIDE - moved[touching], abs=1e-9)
    assert 0.9 * SLIDE < nodal["slip"][touching, 0].min()
    assert np.all(nodal["slip"][~touching, 0] == 0)
    # after pressing alone (first frames) nothing has slipped far: the contact sticks
    assert np.abs(frames[1][1]["slip"]).max() < 1e-3
    assert cellwise["von_mises"][0].max() > 0


def test_the_rigid_body_moves_with_its_prescribed_motion(block_2d):
    points, cells, frames = read(block_2d / "rigid.xdmf")
    assert cells[0].type == "line" and len(cells[0].data) == 4  # the flat's outline
    assert [t for t, _, _ in frames] == pytest.approx([0.5, 1.0, 4 / 3, 5 / 3, 2.0])
    assert frames[-1][1]["displacement"][:, 0] == pytest.approx(SLIDE, rel=1e-12)
    assert frames[0][1]["displacement"][:, 0] == pytest.approx(0.0, abs=1e-15)


def test_3d_series_thinned_by_every(tmp_path):
    """3-D, every = 2 of 5 increments: frames 2 and 4, and the last of each step (2 and 5)."""
    run_contact(friction_block(3, every=2), tmp_path)
    points, cells, frames = read(tmp_path / "fields.xdmf")
    assert cells[0].type == "tetra"
    assert [t for t, _, _ in frames] == pytest.approx([1.0, 5 / 3, 2.0])
    assert set(frames[0][1]) == NODE_FIELDS and set(frames[0][2]) == CELL_FIELDS
    _, rigid_cells, rigid_frames = read(tmp_path / "rigid.xdmf")
    assert rigid_cells[0].type == "triangle" and len(rigid_frames) == 3  # the flat punch's surface
    assert rigid_frames[-1][1]["displacement"][:, 0] == pytest.approx(SLIDE, rel=1e-12)
    _, nodal, _ = frames[-1]
    touching = nodal["contact_pressure"][:, 0] > 0
    assert touching.any() and np.all(nodal["contact_status"][touching, 0] == 2)


def test_a_killed_run_keeps_the_frames_it_finished(tmp_path):
    out = tmp_path / "case"
    command = [sys.executable, "-m", "femcontact", "run", str(ROOT / "scenes" / "wedging_2d.toml"), "--quiet",
               "--set", "mesh.resolution=0.5", "--set", "steps.0.increments=40", "--set", "outputs.fields=true",
               "--out", str(out)]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and process.poll() is None:
        if len(list((out / "fields").glob("0*.h5"))) >= 3:
            break
        time.sleep(0.01)
    process.send_signal(signal.SIGKILL)
    process.wait()
    _, _, frames = read(out / "fields.xdmf")
    assert len(frames) >= 2
    assert [t for t, _, _ in frames] == pytest.approx([0.025 * (k + 1) for k in range(len(frames))])
    assert all(set(point_data) == NODE_FIELDS for _, point_data, _ in frames)


def test_the_final_contact_fields_integrate_to_the_contact_forces(tmp_path):
    """fields.npz of a wedged peg: the lumped pressure and tangential traction over each zone
    integrate to the zone's contact force in history.csv, which sums the same integrals from the
    contact residual, the sharp corner's point force included: equal to round-off (1e-9 relative).
    At this mesh one node of block A's corner presses the peg's flat side and the peg's corner
    presses wall B between two nodes: the normal is one across each zone. The fields are those of
    a frame, each node once; the wedged peg sticks."""
    from wedged_fields import WEDGED, WEDGING_SCENE, contact_forces, read_fields

    from femcontact.api import load_scene
    from femcontact.outputs.history import read_history

    run_contact(load_scene(WEDGING_SCENE, WEDGED), tmp_path)
    fields = read_fields(tmp_path / "fields.npz")
    assert set(NODE_FIELDS) | {"contact_area", "von_mises", "stress"} <= set(fields)
    assert len(np.unique(fields["points"], axis=0)) == len(fields["points"])
    history = read_history(tmp_path / "history.csv")
    forces = contact_forces(fields)
    assert [touching for _, touching in forces.values()] == [1, 2]
    for zone, (force, _) in forces.items():
        assert force == pytest.approx(history[f"contact_{zone}_force"][-1], rel=1e-9)
        assert force > 5.0  # wedged: a residual force of several N per mm at both contacts
    assert np.all(fields["contact_status"][fields["contact_pressure"] > 0] == 1)
    assert np.all(fields["contact_status"][fields["contact_pressure"] == 0] == 0)
    # the stress picture may show the contact pressure instead, its colours up to the largest
    from femcontact.outputs.snapshot import render

    info = render(tmp_path / "fields.npz", tmp_path / "pressure.png", zoom="contact_B", percentile=100.0,
                  field="contact_pressure")
    top = fields["contact_pressure"].max()
    assert info["peak"]["value"] == top and info["ranges"][0] == pytest.approx((0.0, top))
    assert (tmp_path / "pressure.png").stat().st_size > 0


def test_a_run_stopped_mid_step_keeps_its_last_increments_contact_fields(block_2d, tmp_path):
    """Without a series, fields.npz of a drag stopped by its stop condition after 2 of its 3
    increments holds that increment's contact state as the series' frame at the same time shows
    it: read before the increment was committed (committing moves the friction anchors to the
    slipping nodes, after which they would read as sticking), slip measured since the drag began."""
    scene = friction_block(2)
    scene["outputs"]["fields"] = False
    scene["steps"][1]["stop"] = {"column": "rigid_x", "value": 0.5 * SLIDE}
    run_contact(scene, tmp_path)
    assert not (tmp_path / "fields.xdmf").exists()
    final = np.load(tmp_path / "fields.npz")
    _, _, frames = read(block_2d / "fields.xdmf")
    time, nodal, _ = frames[3]
    assert time == pytest.approx(5 / 3)
    touching = nodal["contact_pressure"][:, 0] > 0
    assert touching.sum() >= 20 and np.all(final["contact_status"][touching] == 2)
    for name in ("displacement", "contact_pressure", "tangential_traction", "contact_status", "slip", "gap"):
        assert final[name] == pytest.approx(nodal[name].reshape(final[name].shape), rel=1e-12, abs=1e-15), name
