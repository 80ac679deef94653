"""Pseudo-transient continuation gives the same answer on 1 and 2 ranks (run under mpirun -n 2).

The hard case of tests/verification/test_hard_cases.py (a peg turned upright against the left
wall by a push down and to the left) solved on both ranks together and on each rank alone: tilt
and contact forces agree to the solver tolerance (residual 1e-6 N against forces of 0.1-0.4 N)."""
from dataclasses import replace
from pathlib import Path

import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_2d.toml"
CASE = ["contact.mu=0.6719", "hole.width=40.01351", "peg.insertion_depth=5.372", "materials.hole.nu=0.4252",
        "steps.0.force=[-0.373, -0.1157]", "steps.0.increments=1", "mesh.resolution=0.35"]


def pushed(comm) -> dict:
    scene = load_scene(SCENE, CASE)
    simulation = Simulation(scene, comm)
    simulation.run_step(0, scene["steps"][0])
    return simulation.history[-1]


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_match_one_rank():
    both, alone = pushed(MPI.COMM_WORLD), pushed(MPI.COMM_SELF)
    assert both["stabilization_force"] == alone["stabilization_force"] == 0.0
    for key in ("contact_A_Fx", "contact_A_Fy"):
        assert both[key] == pytest.approx(alone[key], abs=1e-5)
    assert both["rigid_rz"] == pytest.approx(alone["rigid_rz"], rel=1e-4)


LIFTED = ["mesh.resolution=0.35", "contact.mu=0.3775", "hole.width=40.002656", "peg.insertion_depth=0.5342",
          "materials.hole.nu=0.3931", "steps.0.force=[-72.45, 22.27]", "steps.0.increments=1", "solver.max_cuts=0"]


def travel(comm):
    """The pose change with which pseudo-transient continuation gave up (after 120 Newton
    iterations) on a push that levers the peg out of the hole (tests/verification/test_no_equilibrium.py).
    Up to there 1 and 2 ranks agree to all printed digits; further on, the failing path itself
    amplifies round-off (its line searches fall from residuals of 1e5 N to 1e2 N), and by 150
    iterations the two travels differ by 20 %."""
    from femcontact.solver.stepping import SimulationFailed

    scene = load_scene(SCENE, LIFTED)
    simulation = Simulation(scene, comm)
    simulation.options = simulation.newton.options = replace(simulation.options, pseudo_iterations=120)
    with pytest.raises(SimulationFailed):
        simulation.run_step(0, scene["steps"][0])
    return simulation.pseudo_travel[0]


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_the_travel_that_lifts_a_peg_out_is_the_same_on_two_ranks():
    both, alone = travel(MPI.COMM_WORLD), travel(MPI.COMM_SELF)
    assert both[1] > 0.5342 and alone[1] > 0.5342  # up by more than the insertion depth
    assert both == pytest.approx(alone, rel=1e-3, abs=1e-6)
