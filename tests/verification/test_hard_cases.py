"""Hard cases of the stability sweep (`make stability`) converge: regression tests on coarse meshes.

A push down and to the left on the top of a peg leaning in two-point contact (mu 0.67, the rigid
two-point statics need 0.13: `references.two_point_statics`): under this load the lower contact
(the peg's corner on the right wall) would have to pull, so it opens, and the peg pivots on the
single node at the left block's corner with no stiffness against turning. It turns clockwise until
it stands against the left wall, upright, and rests there: pressed by -Fx, held by friction
(|Fy / Fx| = 0.31 < mu). Newton alone and the stabilisation's continuation fail here (the body
must travel 2.5e-3 rad to the contact that holds it); pseudo-transient continuation
(`Simulation.pseudo_transient_solve`) converges on the exact equations.
"""
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_2d.toml"
PUSH = [-0.373, -0.1157]  # N, on the peg top
CASE = ["contact.mu=0.6719", "hole.width=40.01351", "peg.insertion_depth=5.372", "materials.hole.nu=0.4252",
        f"steps.0.force={PUSH}", "steps.0.increments=1", "mesh.resolution=0.35"]


@pytest.fixture(scope="module")
def pushed():
    scene = load_scene(SCENE, CASE)
    simulation = Simulation(scene, MPI.COMM_WORLD)
    tilt = simulation.problem.rigid.tilt()
    simulation.run_step(0, scene["steps"][0])
    return tilt, simulation.history[-1]


def test_the_peg_turns_upright_against_the_left_wall(pushed):
    tilt, row = pushed
    # placed in two-point contact: d cos(tilt) + l_d sin(tilt) = D
    assert 40.0 * np.cos(tilt) + 5.372 * np.sin(tilt) == pytest.approx(40.01351, abs=1e-9)
    # upright to the wall's flatness under the contact's penetration (micrometres over the depth)
    assert abs(np.radians(row["tilt_deg"])) < 1e-3 * tilt
    assert row["contact_B_force"] == 0.0  # the right wall lets go
    assert row["active_nodes"] > 5  # the peg's flank lies along the left wall


def test_the_exact_equations_hold(pushed):
    _, row = pushed
    assert row["stabilization_force"] == 0.0  # no spring left: the converged state is an equilibrium
    # the left wall alone balances the push (to the solver's tolerance, 1e-6 N)
    assert row["contact_A_Fx"] == pytest.approx(PUSH[0], abs=1e-5)
    assert row["contact_A_Fy"] == pytest.approx(PUSH[1], abs=1e-5)
    assert abs(row["contact_A_Fy"]) < row["contact_A_Fx"] * -0.6719  # inside the friction cone


def test_the_peg_turns_upright_at_the_sweep_mesh():
    # the same push at the sweep's own mesh, in the scene's increments: on the way upright the peg
    # turns freely until its flank meets the wall, so along a Newton step the slope R . d stays
    # level and then jumps where that contact closes; the line search bisects towards the jump
    # there. Interpolating the slope instead crept up by 1e-3 of the step per iteration, and the
    # push failed at t = 0.027 s after 8 cuts.
    case = [item for item in CASE if not item.startswith(("steps.0.increments", "mesh.resolution"))]
    scene = load_scene(SCENE, case + ["mesh.resolution=1.154"])
    simulation = Simulation(scene, MPI.COMM_WORLD)
    simulation.run_step(0, scene["steps"][0])  # raises SimulationFailed where an increment does not converge
    row = simulation.history[-1]
    assert row["stabilization_force"] == 0.0
    assert row["contact_B_force"] == 0.0  # the right wall lets go
    assert row["contact_A_Fx"] == pytest.approx(PUSH[0], abs=1e-5)
    assert row["contact_A_Fy"] == pytest.approx(PUSH[1], abs=1e-5)


# A push (144.8 N down and to the left, mu 0.246) that presses the peg's sharp lower corner into
# the right wall hard enough to dent it; on the release the corner slides back across a wall node
# sitting in the dimple its own force made. With one normal per wall facet the corner lies under
# that node on neither facet, its force vanishes there and Newton cycles (the release failed at
# t = 1.9035 s at this mesh); the surface smoothed at its nodes (`effects/rigid_corners.py`)
# carries the force across the node.
CORNER_CASE = ["contact.mu=0.246", "hole.width=40.004409", "peg.insertion_depth=2.3", "materials.hole.nu=0.4869",
               "steps.0.force=[-144.8,-76.83]", "mesh.resolution=0.6"]


def test_a_sharp_corner_slides_back_across_the_node_it_dents():
    scene = load_scene(SCENE, CORNER_CASE)
    simulation = Simulation(scene, MPI.COMM_WORLD)
    simulation.run()  # raises SimulationFailed where an increment does not converge
    released = simulation.history[-1]
    assert released["step"] == "release"
    assert released["stabilization_force"] == 0.0
    # unloaded, the two walls balance each other (solver tolerance 1e-6 N) and still hold the peg
    assert released["contact_A_Fx"] + released["contact_B_Fx"] == pytest.approx(0.0, abs=1e-5)
    assert released["contact_A_Fy"] + released["contact_B_Fy"] == pytest.approx(0.0, abs=1e-5)
    assert abs(released["contact_A_Fx"]) > 1.0  # 153.7 N at this mesh: the peg stays wedged


# Pushes down and to the left that turn a leaning peg upright against the left wall, as above, but
# from leans 5 and 29 times as steep (0.68 and 4.26 deg against 0.15 deg: the stability sweep's
# cases 6e2623710d75 and 3084f09e7346 on a coarse mesh). The peg must pivot on the left block's
# corner by 0.012 and 0.074 rad with nothing resisting the turn but a steady unbalanced moment:
# pseudo-transient continuation gathers speed along the turn (its momentum), and each pseudo step
# commits the friction anchors, so the flank that slid onto the wall sticks where the peg comes to
# rest. Without them both pushes fail after 8 cuts in the first increment that turns the peg
# (t = 0.0195 and 0.0227 s).
#
# 2d06014472c3 (mu 0.325; the rigid two-point statics need 0.151), at its own mesh: the first
# increment's continuation fails once at each stiffer spring as the flank reaches the wall and gives
# up at its sixth failure; the cuts then follow the load to t = 0.029 s and fail there at every cut.
# In that last try the continuation counts only failures in a row and comes to rest upright; counted
# in all it gave up and the case failed after 8 cuts. At resolutions 0.35-1.4 the same push
# converges before the last try, so only this mesh tests it (solve 81 s).
TURNING_PUSHES = {
    "6e2623710d75": (["contact.mu=0.7931", "hole.width=40.0608", "peg.insertion_depth=5.351",
                      "materials.hole.nu=0.2596", "mesh.resolution=0.35"], [-0.2886, -0.1026]),
    "3084f09e7346": (["contact.mu=0.6817", "hole.width=40.3733", "peg.insertion_depth=6.512",
                      "materials.hole.nu=0.2796", "mesh.resolution=0.35"], [-0.5869, -0.2048]),
    "2d06014472c3": (["contact.mu=0.3248", "hole.width=40.3382", "peg.insertion_depth=7.848",
                      "materials.hole.nu=0.4893", "mesh.resolution=1.63"], [-0.1462, -0.03327]),
}


@pytest.mark.parametrize("case", sorted(TURNING_PUSHES))
def test_a_push_turns_the_peg_upright_from_far(case):
    overrides, push = TURNING_PUSHES[case]
    scene = load_scene(SCENE, overrides + [f"steps.0.force={push}"])
    simulation = Simulation(scene, MPI.COMM_WORLD)
    tilt = simulation.problem.rigid.tilt()
    simulation.run_step(0, scene["steps"][0])  # raises SimulationFailed where an increment does not converge
    row = simulation.history[-1]
    assert row["stabilization_force"] == 0.0  # the exact equations hold
    assert abs(np.radians(row["tilt_deg"])) < 1e-3 * tilt  # upright
    assert row["contact_B_force"] == 0.0  # the right wall lets go
    # the left wall alone balances the push (solver tolerance 1e-6 N), inside its friction cone
    assert row["contact_A_Fx"] == pytest.approx(push[0], abs=1e-5)
    assert row["contact_A_Fy"] == pytest.approx(push[1], abs=1e-5)
    assert abs(row["contact_A_Fy"]) < -row["contact_A_Fx"] * scene["contact"]["mu"]


# A push of 334.7 N down and to the left on a peg with little friction (mu 0.0196): the stability
# sweep's d7b784a815f1 at its own mesh (at resolutions 0.5 and 0.7 the push finds no equilibrium
# at t = 0.0047 s, with or without the reach). Its first increment at full length fails plain
# Newton and the stabilisation's continuation; pseudo-transient continuation, which takes the
# whole increment's load at once, then carried the peg 16 mm down the hole in 1,500 Newton
# iterations (43 s) before it gave up, where half the increment converges in 7. So in an
# increment that can still be cut, the continuation gives up as soon as the peg has gone
# `pseudo_reach` contact element sizes (`Simulation.beyond_reach`), and the cut follows the load.
SLIDING_PUSH = ["contact.mu=0.01959", "hole.width=40.04197", "peg.insertion_depth=8.883",
                "materials.hole.nu=0.4472", "steps.0.force=[-334.7,-96.68]", "mesh.resolution=1.106"]


def test_pseudo_transient_continuation_gives_up_past_its_reach_where_a_cut_is_left():
    from femcontact.solver.newton import BodyGone, NewtonFailure

    scene = load_scene(SCENE, SLIDING_PUSH)
    simulation = Simulation(scene, MPI.COMM_WORLD)
    p = simulation.problem
    step = scene["steps"][0]
    load = simulation.schedule.load(0, step["duration"] / step["increments"], step["duration"] / step["increments"])
    start = p.state()
    p.begin_increment(load)
    for way in (simulation.plain_solve, simulation.stabilized_solve):
        with pytest.raises(NewtonFailure):
            way(load)
        p.restore(start)
        simulation.prescribe(load)
    pose = p.rigid.values.copy()
    with pytest.raises(BodyGone):
        simulation.pseudo_transient_solve(load, gone=simulation.beyond_reach)
    reach = simulation.options.pseudo_reach * p.contact_size
    travel = p.rigid_length(p.rigid.values - pose)
    assert reach < travel < 2 * reach  # given up at the first pseudo step past the reach
    assert simulation.pseudo_transient_exhausted == 0  # and not tried again in the step
    p.restore(start)
    simulation.pseudo_transient_exhausted = None

    simulation.run_step(0, step)  # raises SimulationFailed where an increment does not converge
    first, loaded = simulation.history[0], simulation.history[-1]
    assert first["dt"] == pytest.approx(load.dt / 2)  # the cut, not the continuation, took the first increment
    assert loaded["stabilization_force"] == 0.0
    # the two walls carry the push (solver tolerance 1e-6 N): the peg is held, not gone
    assert loaded["contact_A_Fx"] + loaded["contact_B_Fx"] == pytest.approx(-334.7, abs=1e-5)
    assert loaded["contact_A_Fy"] + loaded["contact_B_Fy"] == pytest.approx(-96.68, abs=1e-5)


# seed 1's 951fab131e93 at a coarse mesh: a push the rigid peg cannot hold (mu 0.057, the
# two-point statics need 0.23); plain Newton's |R| stalls at 2.76e-2 N
STALLING_PUSH = ["contact.mu=0.05699", "hole.width=40.001177", "peg.insertion_depth=9.25",
                 "materials.hole.nu=0.4731", "steps.0.force=[-0.3546,-0.1544]", "mesh.resolution=0.35"]


def test_a_newton_solve_that_stalls_stops_early_and_loses_nothing():
    import dataclasses

    from femcontact.solver.newton import NewtonFailure

    scene = load_scene(SCENE, STALLING_PUSH)
    simulation = Simulation(scene, MPI.COMM_WORLD)
    p, options = simulation.problem, simulation.options
    step = scene["steps"][0]
    load = simulation.schedule.load(0, step["duration"] / step["increments"], step["duration"] / step["increments"])
    start = p.state()
    p.begin_increment(load)
    histories = []
    for stall_iterations in (options.stall_iterations, options.max_iterations + 1):  # the stop, then none
        simulation.options = simulation.newton.options = dataclasses.replace(options, stall_iterations=stall_iterations)
        p.restore(start)
        simulation.prescribe(load)
        with pytest.raises(NewtonFailure) as failure:
            simulation.plain_solve(load)
        histories.append((str(failure.value), failure.value.history))
    (reason, stopped), (_, full) = histories
    assert reason.startswith("no progress") and len(stopped) < options.max_iterations // 2
    last = stopped[-options.stall_iterations - 1:]
    assert all(abs(b - a) <= options.stall_change * a for a, b in zip(last, last[1:]))
    assert len(full) == options.max_iterations + 1  # without the stop: every iteration, no convergence
    assert full[: len(stopped)] == stopped  # the same iterations up to the stop
    assert min(full) > (1 - 1e-3) * stopped[-1]  # the iterations the stop saves lower |R| by < 0.1 %
