"""Wedging, the thesis ch. 3 (its 2-D cases): classification, balance, tilt, stresses.

The thesis' four cases (d 40, D 40.1, mu 0.2, push Fx = -5, Fy = 1 N on the peg top, then
release) on a coarse mesh (`mesh.resolution = 0.5`, ~4x fewer triangles than the default;
docs/wedging.md checks that it classifies every case like resolution 1 and 2). Published:
l_d = 4, 5, 6 wedge with |R_A + R_B| < 1e-3 N, l_d = 10 ends with zero reactions; the tilt
rises under load and drops slightly on release; stresses stay elastic (yield 210 MPa).
"""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families.wedging import metrics as wedging
from femcontact.families import load_scene

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_2d.toml"
RESOLUTION = 0.5
YIELD = 210.0


def run(tmp_path_factory, depth: float) -> dict:
    from femcontact.families.case import run_contact as run_scene

    scene = load_scene(SCENE, [f"peg.insertion_depth={depth}", f"mesh.resolution={RESOLUTION}"])
    return run_scene(scene, tmp_path_factory.mktemp(f"wedging_{depth:g}"))["metrics"]


@pytest.fixture(scope="module")
def cases(tmp_path_factory) -> dict:
    return {depth: run(tmp_path_factory, depth) for depth in (4.0, 5.0, 6.0, 10.0)}


@pytest.mark.parametrize("depth", [4.0, 5.0, 6.0])
def test_published_cases_wedge_balanced_and_collinear(cases, depth):
    m = cases[depth]
    assert m["wedged"], m["wedge_reason"]
    assert m["analytic_wedged"]
    # held: the residual reactions are of the order of the load (5.1 N), far above the floor
    assert m["residual_force_A"] > 1.0 and m["residual_force_B"] > 1.0
    assert m["imbalance"] < 1e-3  # the thesis' criterion |R_A + R_B| < 1e-3 N, relative here
    assert abs(m["residual_force_A_x"] + m["residual_force_B_x"]) < 1e-3
    assert abs(m["residual_force_A_y"] + m["residual_force_B_y"]) < 1e-3
    # as published, R_A pushes the block outwards (+x on A) and down (-y)
    assert m["residual_force_A_x"] > 0 and m["residual_force_A_y"] < 0
    # a wedged peg is a two-force body: both reactions along the line of the contact points
    assert m["angle_A_deg"] < wedging.ANGLE_TOL_DEG and m["angle_B_deg"] < wedging.ANGLE_TOL_DEG
    # and that line lies inside the friction cone (the wedging condition itself)
    assert np.degrees(np.arctan2(-m["residual_force_A_y"], m["residual_force_A_x"])) < np.degrees(np.arctan(0.2))
    assert m["stabilization_force_released"] == 0.0


def test_residual_force_decreases_with_depth(cases):
    """Thesis: 13.26, 11.72, 9.40 N for l_d = 4, 5, 6 (our blocks are stiffer: smaller values, same trend)."""
    forces = [cases[d]["residual_force_A"] for d in (4.0, 5.0, 6.0)]
    assert forces[0] > forces[1] > forces[2]


def test_beyond_l_max_does_not_wedge(cases):
    m = cases[10.0]
    assert not m["analytic_wedged"]
    assert not m["wedged"]
    assert m["wedge_reason"] in ("no residual force", "no equilibrium after release (stabilised state)")
    # the residual is at most the stabilised solver's leftover, < FORCE_FLOOR of the 5.1 N push
    assert m["residual_force_A"] < wedging.FORCE_FLOOR * np.hypot(5.0, 1.0)
    assert m["elastic_energy"] < 1e-3 * cases[5.0]["elastic_energy"]


@pytest.mark.parametrize("depth", [4.0, 5.0, 6.0])
def test_tilt_rises_under_load_and_drops_slightly_on_release(cases, depth):
    m = cases[depth]
    assert m["tilt_initial_deg"] == pytest.approx({4.0: 1.6784, 5.0: 1.2560, 6.0: 1.0148}[depth], abs=2e-3)
    assert m["tilt_loaded_deg"] > m["tilt_initial_deg"]
    assert m["tilt_released_deg"] < m["tilt_loaded_deg"]
    assert m["tilt_released_deg"] > m["tilt_initial_deg"]  # still deformed: held by the stored energy
    assert m["elastic_energy"] > 0


@pytest.mark.parametrize("depth", [4.0, 5.0, 6.0, 10.0])
def test_stresses_stay_below_yield(cases, depth):
    """On this coarse mesh. The peak sits under the peg's sharp rigid corner on wall B and at the
    mouth corner of block A, a stress concentration that grows with refinement: at resolution 1
    l_d = 4 peaks at 238 MPa and l_d = 3 at 282 MPa (5, 6: 194, 178), see docs/wedging.md."""
    assert cases[depth]["max_von_mises"] < YIELD
    assert not cases[depth]["yielded"]


def test_a_placed_corner_touches_with_stiffness_and_no_force():
    """Two-point placement puts the peg's lower corner on the block wall to round-off (the gap
    came out 3.6e-15 mm on the default mesh, 0 on the coarse one): it must enter Newton's first
    Jacobian with the penalty stiffness gamma E, else the peg turns into the wall unopposed in
    the first iteration; its force stays zero until it presses."""
    from femcontact.solver.stepping import Simulation
    from mpi4py import MPI

    scene = load_scene(SCENE)
    corners = next(c for c in Simulation(scene, MPI.COMM_WORLD).problem.components if c.name == "rigid_corners")
    contributions, pressing = corners.contributions(with_jacobian=True)
    touching = MPI.COMM_WORLD.allreduce(len(contributions), op=MPI.SUM)
    assert touching == 1 and pressing == 0
    kappa = float(corners.problem.constants["gamma"].value * corners.problem.constants["E"].value)
    for _, entries, dC_du, _ in contributions:
        assert np.abs(entries).max() == 0.0
        assert np.abs(dC_du).max() == pytest.approx(kappa, rel=0.1)


# -- the thesis set-up (scenes/wedging_thesis_2d.toml, docs/wedging.md "The thesis set-up") --------

THESIS_SCENE = Path(__file__).parents[2] / "scenes" / "wedging_thesis_2d.toml"
THESIS_DATA = Path(__file__).parents[1] / "data" / "wedging_thesis.csv"
# Tolerances on ours / thesis: the set-up's deviation measured on this mesh (l_d = 5: tilt change
# 0.852 deg, +5.7 %, |R_A| 11.58 N, -1.7 %; l_d = 6: 0.546 deg, +14.9 %, 10.56 N, +11.5 %) plus the
# scatter of |R_A| between compliances next to the chosen one (11.58-12.18 N for E / 70 to E / 60 at
# l_d = 5: the slipping contact nodes change in steps), so that a set-up that lost either change
# fails (default blocks: tilt change 0.01x; a 10-mm peg: |R_A| 0.63-0.71x; docs/wedging.md).
THESIS_TOLERANCE = {5.0: (0.20, 0.12), 6.0: (0.30, 0.25)}  # l_d: (tilt change, residual) relative


@pytest.fixture(scope="module")
def thesis_cases(tmp_path_factory) -> dict:
    import csv

    from femcontact.families.case import run_contact as run_scene

    with open(THESIS_DATA, newline="") as stream:
        published = {float(r["insertion_depth_mm"]): r for r in csv.DictReader(stream)}
    out = {}
    for depth in THESIS_TOLERANCE:
        scene = load_scene(THESIS_SCENE, [f"peg.insertion_depth={depth}", f"mesh.resolution={RESOLUTION}"])
        out[depth] = (run_scene(scene, tmp_path_factory.mktemp(f"thesis_{depth:g}"))["metrics"], published[depth])
    return out


@pytest.mark.parametrize("depth", sorted(THESIS_TOLERANCE))
def test_thesis_setup_reproduces_tilt_change_and_residual(thesis_cases, depth):
    m, row = thesis_cases[depth]
    assert m["wedged"], m["wedge_reason"]
    change = float(row["angle_step1_deg"]) - float(row["angle_initial_deg"])
    residual = float(np.hypot(float(row["RA_Fx_N"]), float(row["RA_Fy_N"])))
    tilt_tol, force_tol = THESIS_TOLERANCE[depth]
    assert m["tilt_change_deg"] == pytest.approx(change, rel=tilt_tol)
    assert m["residual_force_A"] == pytest.approx(residual, rel=force_tol)
    assert m["thesis_residual_force_A"] == pytest.approx(residual, rel=1e-9)
    # the reaction's direction is the thesis' to a fraction of a degree (4.81 and 6.72 deg below horizontal)
    published = np.degrees(np.arctan2(-float(row["RA_Fy_N"]), float(row["RA_Fx_N"])))
    assert np.degrees(np.arctan2(-m["residual_force_A_y"], m["residual_force_A_x"])) == pytest.approx(published, abs=0.5)
    # as published, the tilt drops slightly on release (by 0.02-0.03 deg)
    assert 0 < m["tilt_loaded_deg"] - m["tilt_released_deg"] < 0.05


def test_thesis_setup_keeps_the_case_order(thesis_cases):
    """Thesis: the deeper peg tilts less under the push and is held less (0.806 > 0.475 deg, 11.77 > 9.46 N)."""
    shallow, deep = thesis_cases[5.0][0], thesis_cases[6.0][0]
    assert shallow["tilt_change_deg"] > deep["tilt_change_deg"]
    assert shallow["residual_force_A"] > deep["residual_force_A"]


def test_a_rigid_peg_with_a_tip_chamfer_wedges_on_the_chamfer_edge(tmp_path):
    """A 0.5 mm x 45 deg chamfer on the rigid peg's tip (l_d = 5): placed with the chamfer's top
    edge on wall B, the peg wedges like the sharp one (balanced, both reactions on the line of the
    contacts), and contact B stays at that edge (within 0.02 mm; its corner is a tracked point)."""
    from femcontact.families.case import run_contact
    from geometry.placement import peg_pose

    scene = load_scene(SCENE, ["peg.chamfer_width=0.5", f"mesh.resolution={RESOLUTION}"])
    m = run_contact(scene, tmp_path)["metrics"]
    assert m["wedged"], m["wedge_reason"]
    assert m["residual_force_A"] > 1.0 and m["imbalance"] < 1e-3
    assert m["angle_A_deg"] < wedging.ANGLE_TOL_DEG and m["angle_B_deg"] < wedging.ANGLE_TOL_DEG
    assert m["release.contact_B_y"] == pytest.approx(peg_pose(scene).points["contact_B"][1], abs=0.02)
