"""The snap-fit metrics do not depend on the number of MPI ranks (run under mpirun -n 2): the
contract scene (two springs) on both ranks against each rank alone on MPI.COMM_SELF, insertion
only (the withdrawal stays on the shank) to keep the test short."""
from pathlib import Path

import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.families.snap_fit.metrics import snap_fit_metrics
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "snap_fit_2d.toml"
KEYS = ("insertion_force_ratio", "final_contact_force", "peak_insertion_force", "peak_withdrawal_force",
        "root_stress")


def run(comm) -> dict:
    simulation = Simulation(load_scene(SCENE, ["mesh.resolution=0.6", "steps.0.increments=20",
                                               "steps.1.increments=2", "steps.1.motion.y=-0.7"]), comm)
    simulation.run()
    return snap_fit_metrics(simulation)


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_match_one_rank():
    parallel, serial = run(MPI.COMM_WORLD), run(MPI.COMM_SELF)
    for key in KEYS:  # forces ~1 N, solver tolerance 1e-5 N
        assert parallel[key] == pytest.approx(serial[key], rel=1e-5), key
    assert parallel["jammed"] is serial["jammed"] is False


SCENE_3D = SCENE.with_name("snap_fit_3d.toml")


def run_3d(comm) -> dict:
    simulation = Simulation(load_scene(SCENE_3D, ["mesh.resolution=0.7", "steps.0.motion.y=-0.34",
                                                  "steps.0.increments=8", "steps.1.motion.y=-0.2",
                                                  "steps.1.increments=2"]), comm)
    simulation.run()
    return snap_fit_metrics(simulation)


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_3d_two_ranks_match_one_rank():
    """3-D (scenes/snap_fit_3d.toml, coarser, in over the taper onto the shank and back onto the
    taper): the mesh split over 2 ranks against each rank alone; forces ~1 N, solver tolerance 1e-5 N."""
    parallel, serial = run_3d(MPI.COMM_WORLD), run_3d(MPI.COMM_SELF)
    for key in KEYS + ("withdrawal_force_ratio",):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-5), key
    assert parallel["jammed"] is serial["jammed"] is False
