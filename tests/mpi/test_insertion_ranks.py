"""The 3-D compliant insertion does not depend on the number of MPI ranks (run under mpirun -n 2):
scenes/insertion_3d.toml on a coarse mesh into one-point contact, on both ranks against each rank
alone on MPI.COMM_SELF."""
from pathlib import Path

import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "insertion_3d.toml"
COLUMNS = ("support_Fx", "support_Fz", "support_My", "tilt_xz_deg", "contact_B_force", "contact_B_z")


def run(comm) -> list[dict]:
    # s from 0.7 to 1.5 mm: the edge touches the peg's side at s = 0.86 mm (one-point contact)
    scene = load_scene(SCENE, ["mesh.contact_size=1.0", "mesh.contact_zone=3.0", "steps.0.increments=4",
                               "steps.0.support_motion.z=-0.8"])
    simulation = Simulation(scene, comm)
    simulation.run()
    return simulation.history


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_match_one_rank():
    parallel, serial = run(MPI.COMM_WORLD), run(MPI.COMM_SELF)
    serial_at = {round(row["time"], 12): row for row in serial}
    common = [(p, serial_at[round(p["time"], 12)]) for p in parallel if round(p["time"], 12) in serial_at]
    assert common[-1][0]["time"] == pytest.approx(1.0)  # at least the end of the step
    assert serial[-1]["contact_B_force"] > 0.1  # in contact: the edge pushes the side
    for p, s in common:  # the same load; increments cut on one side only add rows
        for column in COLUMNS:  # forces ~1 N, Newton's tolerance 1e-9 relative
            if s[column] is None:  # no contact yet: no force centre
                assert p[column] is None, column
            else:
                assert p[column] == pytest.approx(s[column], rel=1e-6, abs=1e-9), column
