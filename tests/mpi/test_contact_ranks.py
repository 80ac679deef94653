"""Results do not depend on the number of MPI ranks (run under mpirun -n 2).

The wedging scene is solved on both ranks together and, on each rank alone, on
MPI.COMM_SELF; reactions, tilt and contact forces must agree to the solver tolerance
(residual 1e-6 N against forces of 5-10 N, so 1e-6 relative)."""
import pytest
from mpi4py import MPI

from femcontact.families import resolve_scene
from femcontact.solver.stepping import Simulation

SCENE = {
    "name": "ranks", "dim": 2, "geometry": "peg_in_hole", "effects": ["friction", "plane_strain"],
    "peg": {"width": 40.0, "length": 10.0, "insertion_depth": 5.0}, "hole": {"width": 40.1},
    "contact": {"mu": 0.2}, "mesh": {"resolution": 0.5},
    "steps": [{"name": "load", "increments": 4, "force": [-5.0, 1.0]}, {"name": "release", "increments": 4}],
}
KEYS = ("reaction_support_A_x", "reaction_support_A_y", "reaction_support_B_x", "reaction_support_B_y",
        "contact_A_Fx", "contact_B_Fx", "tilt_deg", "rigid_x", "rigid_y")


def run(comm) -> dict:
    simulation = Simulation(resolve_scene(SCENE), comm)
    simulation.run()
    return simulation.step_end_rows()


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_match_one_rank():
    parallel = run(MPI.COMM_WORLD)
    serial = run(MPI.COMM_SELF)
    for step in ("load", "release"):
        for key in KEYS:
            scale = max(abs(serial[step][key]), 1e-3 if key.startswith(("tilt", "rigid")) else 1.0)
            assert abs(parallel[step][key] - serial[step][key]) / scale < 1e-6, (step, key)
    assert parallel["release"]["reaction_support_A"] > 1.0
