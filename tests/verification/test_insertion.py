"""The compliant support (effects/compliant_support.py) against hand calculations, and the
insertion metrics (femcontact/families/insertion/metrics.py).

The peg hangs in a wide hole (D = 14, d = 10, centred, no contact), so the support alone holds it: a load W at the
compliance centre C displaces C by K^-1 W exactly; a force at the peg top turns the peg about C,
a one-unknown equilibrium solved here by bisection; a gripper motion carries the peg along
rigidly. Meshes are coarse: the hole is never touched.
"""
import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.errors import InputError
from femcontact.solver.stepping import Simulation

SCENE = str(Path(__file__).resolve().parents[2] / "scenes" / "insertion_2d.toml")
FREE = ["hole.width=14.0", "peg.offset=0.0", "peg.insertion_depth=2.0", "steps.0.increments=1", "mesh.contact_size=1.0", "mesh.size_max=3.0",
        "mesh.contact_zone=1.0", "solver.rtol=1e-12", "solver.atol=1e-9",
        "steps.0.support_motion.y=0.0"]
THREE_D = ["dim=3", "effects=['compliant_support']", "hole.kind='single'", "hole.width=16.0", "hole.depth=6.0",
           "hole.block_width=4.0", "hole.bottom_thickness=2.0", "hole.chamfer_width=0.0", "peg.insertion_depth=2.0",
           "peg.offset=0.0", "mesh.contact_size=2.0", "mesh.size_max=4.0", "mesh.contact_zone=2.0",
           "support.model='rcc'", "steps.0.support_motion.y=0.0", "steps.0.stop.column=''"]


def run(*overrides):
    scene = load_scene(SCENE, FREE + list(overrides))
    simulation = Simulation(scene, comm=MPI.COMM_WORLD)
    simulation.run()
    return simulation, simulation.history[-1]


def test_load_at_the_compliance_centre_gives_K_inverse_W():
    """A coupled, symmetric K (model 'matrix'); C at the reference point (L_g = length/2 = 10), so
    the load's arm vanishes: q = K^-1 W, tip = C + q_t + R(q_rz)(tip0 - C0)."""
    K = np.array([[20.0, 5.0, 40.0], [5.0, 300.0, -30.0], [40.0, -30.0, 3000.0]])
    W = np.array([1.5, -2.0, 30.0])
    sim, row = run("support.model='matrix'", f"support.stiffness={K.reshape(-1).tolist()}",
                   "support.compliance_centre=10.0", f"steps.0.force={W[:2].tolist()}",
                   f"steps.0.moment=[{W[2]}]", "steps.0.load_point='reference'")
    q = np.linalg.solve(K, W)
    assert [row["support_qx"], row["support_qy"], row["support_qrz"]] == pytest.approx(q, rel=1e-7)
    assert [row["support_Fx"], row["support_Fy"], row["support_Mz"]] == pytest.approx(-W, rel=1e-7)
    tip0 = np.array([0.0, -2.0])
    centre0 = tip0 + [0.0, 10.0]
    c, s = math.cos(q[2]), math.sin(q[2])
    tip = centre0 + q[:2] + np.array([[c, -s], [s, c]]) @ (tip0 - centre0)
    assert [row["tip_x"], row["tip_y"]] == pytest.approx(tip, abs=1e-9)


def test_force_at_the_peg_top_turns_the_peg_about_the_compliance_centre():
    """Diagonal springs, C at the tip (L_g = 0), Fx at the top (20 mm up the axis): the moment
    about C is -20 cos(theta) Fx, so theta solves K_theta theta = -20 cos(theta) Fx (exact
    rotation, solved by bisection), C moves Fx / K_x, and the support moment balances it."""
    kx, ktheta, Fx = 20.0, 300.0, 4.0
    sim, row = run(f"support.kx={kx}", f"support.ktheta={ktheta}", "support.compliance_centre=0.0",
                   f"steps.0.force=[{Fx}, 0.0]", "steps.0.load_point='peg_top'")
    lo, hi = -1.0, 0.0
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if ktheta * mid + 20 * math.cos(mid) * Fx < 0 else (lo, mid)
    theta = (lo + hi) / 2
    assert row["support_qrz"] == pytest.approx(theta, rel=1e-8)
    assert row["support_qx"] == pytest.approx(Fx / kx, rel=1e-8)
    assert row["support_Mz"] == pytest.approx(20 * math.cos(theta) * Fx, rel=1e-8)
    assert row["tilt_deg"] == pytest.approx(math.degrees(theta), rel=1e-8)


def test_gripper_motion_carries_the_unloaded_peg_rigidly():
    """No load: the peg follows the gripper, turned by rz about C (L_g = 10) and shifted."""
    g = np.array([0.3, -0.2, 0.02])
    sim, row = run("support.compliance_centre=10.0",
                   f"steps.0.support_motion={{x={g[0]}, y={g[1]}, rz={g[2]}}}")
    assert abs(row["support_qx"]) + abs(row["support_qy"]) + abs(row["support_qrz"]) < 1e-9
    tip0 = np.array([0.0, -2.0])
    centre0 = tip0 + [0.0, 10.0]
    c, s = math.cos(g[2]), math.sin(g[2])
    tip = centre0 + g[:2] + np.array([[c, -s], [s, c]]) @ (tip0 - centre0)
    assert [row["tip_x"], row["tip_y"]] == pytest.approx(tip, abs=1e-9)
    assert row["gripper_y"] == pytest.approx(g[1])


def test_support_motion_needs_the_effect():
    with pytest.raises(InputError, match=r"steps\[0\]\.support_motion\.y = -5.2: needs the 'compliant_support'"):
        load_scene(SCENE, ["effects=['friction', 'plane_strain']"])


def test_a_bad_stiffness_matrix_is_refused_naming_the_key():
    """Refused when the scene is loaded, before anything is built."""
    with pytest.raises(InputError, match=r"support.stiffness = \[1.0, 2.0\]: 2 values, expected 9"):
        load_scene(SCENE, ["support.model='matrix'", "support.stiffness=[1.0, 2.0]"])


def test_rcc_support_reduces_to_the_x_z_plane():
    """The RCC design formula (the thesis, ch. 5) in 2-D: K_x = 3 k cos^2, K_z = 6 k sin^2, K_theta = k b^2 sin^2."""
    from femcontact.physics.support import stiffness_matrix

    scene = load_scene(SCENE, ["support.model='rcc'", "support.rcc={b=50.0, "
                       "peg_length=50.0, theta_l=70.0, k=200.0}"])
    c2, s2 = math.cos(math.radians(70)) ** 2, math.sin(math.radians(70)) ** 2
    assert np.diag(stiffness_matrix(scene)) == pytest.approx([600 * c2, 1200 * s2, 200 * 2500 * s2], rel=1e-12)


def test_stiff_hole_insertion_agrees_with_the_analytic_tier():
    """Steel hole, support K_x 20 N/mm, K_theta 3000 N*mm/rad, L_g 10, eps0 0.6, mu 0.1 (the scene),
    0.1 mm increments, a coarse hole mesh (0.5 mm at the walls). The analytic tier is the rigid-hole
    quasi-static solution (references/whitney.py). Measured on this mesh (790 dofs): Fz within 0.10 %
    (chamfer), 0.03 % (one point), 1.3 % (two point: the steel blocks' own compliance, which the rigid
    theory lacks, lowers the force), onset 2.546 against 2.543 mm, peak 2.021 against 2.038 N at
    3.90 against 3.88 mm; tolerances 1 %, 1 %, 3 %, one increment (0.1 mm), 3 %, 0.3 mm."""
    from femcontact.families.insertion.metrics import insertion_metrics

    scene = load_scene(SCENE,
                       ["mesh.contact_size=0.5", "mesh.size_max=3.0", "steps.0.increments=52",
                        "steps.0.support_motion.y=-5.2"])
    simulation = Simulation(scene, comm=MPI.COMM_WORLD)
    simulation.run()
    m = insertion_metrics(simulation)
    assert m["analytic"] and not m["analytic_jams"] and not m["jammed"] and not m["wedged"]
    assert m["fz_error_chamfer"] < 0.01 and m["fx_error_chamfer"] < 0.01
    assert m["fz_error_one_point"] < 0.01 and m["fx_error_one_point"] < 0.01
    assert m["fz_error_two_point"] < 0.03 and m["fx_error_two_point"] < 0.01
    assert m["phase_agreement"] >= 0.95
    assert abs(m["two_point_onset"] - m["analytic_two_point_onset"]) < 0.1
    assert m["peak_force"] == pytest.approx(m["analytic_peak_force"], rel=0.03)
    assert abs(m["peak_depth"] - m["analytic_peak_depth"]) < 0.3


def test_3d_rcc_support_gives_K_inverse_W_with_finite_rotations():
    """3-D: a cylinder in a wide round hole on the RCC (design formula, 6x6), centre at the
    reference point: q = K^-1 W for a force and a moment at C, the rotation a rotation vector
    (R = exp(q_r)), so the tip lands at C0 + q_t + R (tip0 - C0) exactly."""
    from femcontact.physics.support import stiffness_matrix

    data = THREE_D + ["support.rcc.k=20.0", "support.compliance_centre=10.0", "steps.0.increments=1",
                      "steps.0.force=[3.0, -2.0, 1.0]", "steps.0.moment=[200.0, -300.0, 150.0]",
                      "steps.0.load_point='reference'", "solver.rtol=1e-12", "solver.atol=1e-9"]
    scene = load_scene(SCENE, data)
    simulation = Simulation(scene, comm=MPI.COMM_WORLD)
    simulation.run()
    row = simulation.history[-1]
    W = np.r_[scene["steps"][0]["force"], scene["steps"][0]["moment"]]
    q = np.linalg.solve(stiffness_matrix(scene), W)
    names = ("x", "y", "z", "rx", "ry", "rz")
    assert [row[f"support_q{n}"] for n in names] == pytest.approx(q, rel=1e-7, abs=1e-12)
    angle = np.linalg.norm(q[3:])
    k = q[3:] / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    tip0, centre0 = np.array([0.0, 0.0, -2.0]), np.array([0.0, 0.0, 8.0])
    tip = centre0 + q[:3] + R @ (tip0 - centre0)
    assert [row["tip_x"], row["tip_y"], row["tip_z"]] == pytest.approx(tip, abs=1e-9)
    axis = R @ (centre0 - tip0) / 10.0  # the peg axis, tip to centre
    assert row["tilt_xz_deg"] == pytest.approx(math.degrees(math.atan2(-axis[0], axis[2])), abs=1e-9)


def test_rounded_tip_maps_to_the_sharp_peg_with_its_tip_raised():
    """families.insertion.metrics.analytic_problem treats a tip rounded with radius rho as the analytic tier's
    sharp peg with its tip rho higher. Exact two-point geometry of the rounded peg (the rounding's
    centre rho from the left wall, the hole's right edge on the right side at l' from the tip), solved
    for the tilt, against the sharp tier's D = d cos theta + l sin theta at l = l' - rho: the two
    differ by rho (1 - cos theta) in D, so the tilts by that over dD/dtheta (measured: to 2 %):
    1 % of the tilt at l' = 2.5 mm, 0.05 % at 8 mm (d 10, D 10.1, rho 0.5)."""
    from scipy.optimize import brentq

    from femcontact.references.whitney import two_point_tilt
    from femcontact.families.insertion.metrics import analytic_problem

    d, D, rho, r = 10.0, 10.1, 0.5, 5.0
    for l_side in (2.5, 4.0, 6.0, 8.0):
        def wall_gap(theta):  # rounding centre minus its contact position, peg leaning to +x (theta < 0)
            n, a = np.array([math.cos(theta), math.sin(theta)]), np.array([-math.sin(theta), math.cos(theta)])
            tip = np.array([D / 2, 0.0]) - r * n - l_side * a
            return (tip - (r - rho) * n + rho * a)[0] - (-D / 2 + rho)
        exact = brentq(wall_gap, -0.1, 0.0)  # the first root below 0: l_crit < l' - rho
        sharp, l = two_point_tilt(d, D, l_side - rho), l_side - rho
        # D differs by rho (1 - cos theta): the tilt by that over dD/dtheta = l cos theta - d sin theta
        assert sharp - abs(exact) == pytest.approx(rho * (1 - math.cos(sharp)) / (l * math.cos(sharp) - d * math.sin(sharp)),
                                                   rel=0.05)
        assert sharp - abs(exact) < 0.011 * sharp
    scene = load_scene(SCENE, ["peg.corner_radius=0.5", "peg.tilt=-3.0", "peg.offset=0.0"])
    problem, offset = analytic_problem(scene)
    assert problem.lg == pytest.approx(10.0 - 0.5) and offset == pytest.approx(0.5 * math.cos(math.radians(3)))
    assert problem.lateral_error == pytest.approx(0.5 * math.sin(math.radians(3)))


def test_rcc_support_is_the_truss_models_linear_stiffness():
    """Model 'rcc' in 3-D: K equals the RCC truss's small-motion stiffness at its compliance centre
    (femcontact.families.rcc.device.wrench, model 'linear', unit motions; device frame z down the peg: a half
    turn about x, under which this diagonal K is unchanged)."""
    from femcontact.physics.support import stiffness_matrix
    from femcontact.families.rcc.device import Rcc, wrench

    scene = load_scene(SCENE, THREE_D + ["support.rcc={b=43.3, peg_length=25.0, theta_l=60.0, k=30.0}"])
    device = Rcc(43.3, 25.0, 60.0, 30.0)
    truss = np.array([wrench(device, np.eye(6)[j], model="linear") for j in range(6)]).T
    T = np.diag([1.0, -1.0, -1.0, 1.0, -1.0, -1.0])
    assert stiffness_matrix(scene) == pytest.approx(T @ truss @ T, rel=1e-9, abs=1e-9 * np.abs(truss).max())
