"""The plasticity effect gives the same answer on 2 ranks as on 1 (run under mpirun -n 2).

The wedging scene pushed at four times its load, so the hole's corners flow (PEEQ about 0.02):
reactions, contact forces, the peak PEEQ and the plastic zone's area agree to the solver's
tolerance (1e-6 relative), in plane strain and in plane stress."""
import pytest
from mpi4py import MPI

from femcontact.families import resolve_scene
from femcontact.solver.stepping import Simulation

SCENE = {
    "name": "plastic_ranks", "dim": 2, "geometry": "peg_in_hole", "effects": ["friction", "plane_strain", "plasticity"],
    "peg": {"width": 40.0, "length": 10.0, "insertion_depth": 5.0}, "hole": {"width": 40.1},
    "contact": {"mu": 0.2}, "mesh": {"resolution": 0.5}, "plasticity": {"hardening": [[0, 210], [1, 290]]},
    "steps": [{"name": "load", "increments": 4, "force": [-20.0, 4.0]}, {"name": "release", "increments": 2}],
}
KEYS = ("reaction_support_A_x", "reaction_support_B_x", "contact_A_Fx", "contact_B_Fx", "max_peeq", "plastic_zone")


def run(comm, plane: str) -> dict:
    simulation = Simulation(resolve_scene({**SCENE, "effects": ["friction", plane, "plasticity"]}), comm)
    simulation.run()
    return simulation.step_end_rows()


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
@pytest.mark.parametrize("plane", ["plane_strain", "plane_stress"])
def test_two_ranks_match_one_rank_with_plastic_flow(plane):
    parallel = run(MPI.COMM_WORLD, plane)
    serial = run(MPI.COMM_SELF, plane)
    assert serial["load"]["max_peeq"] > 1e-3 and serial["release"]["plastic_zone"] > 0
    for step in ("load", "release"):
        for key in KEYS:
            scale = max(abs(serial[step][key]), 1e-3 if key == "max_peeq" else 1.0)
            assert abs(parallel[step][key] - serial[step][key]) / scale < 1e-6, (step, key, parallel[step][key], serial[step][key])
