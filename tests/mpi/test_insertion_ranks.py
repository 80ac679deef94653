"""The 3-D compliant insertion does not depend on the number of MPI ranks (run under mpirun -n 2):
scenes/insertion_3d.toml on a coarse mesh into one-point contact and on into two-point contact, on
both ranks against each rank alone on MPI.COMM_SELF, with the scene's force along the wall's normal
(`contact.normal = "wall"`, whose smooth-wall nodes are found across the ranks)."""
from pathlib import Path

import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "insertion_3d.toml"
COLUMNS = ("support_Fx", "support_Fz", "support_My", "tilt_xz_deg", "contact_B_force", "contact_B_z")


DESCENTS = [  # s from 0.7 mm: the edge touches the peg's side at s = 0.86 mm, the rim the wall from 2.8 mm
    (["steps.0.increments=4", "steps.0.support_motion.z=-0.8"], ["contact_B_force"]),
    (["steps.0.increments=8", "steps.0.support_motion.z=-2.8"],
     ["contact_A_force", "contact_B_force"])]


def run(comm, descent: list) -> list[dict]:
    scene = load_scene(SCENE, ["mesh.contact_size=1.0", "mesh.contact_zone=3.0", *descent])
    simulation = Simulation(scene, comm)
    simulation.run()
    return simulation.history


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
@pytest.mark.parametrize("descent, touching", DESCENTS, ids=["one_point", "two_point"])
def test_two_ranks_match_one_rank(descent, touching):
    parallel, serial = run(MPI.COMM_WORLD, descent), run(MPI.COMM_SELF, descent)
    serial_at = {round(row["time"], 12): row for row in serial}
    common = [(p, serial_at[round(p["time"], 12)]) for p in parallel if round(p["time"], 12) in serial_at]
    assert common[-1][0]["time"] == pytest.approx(1.0)  # at least the end of the step
    for column in touching:  # in contact: the edge pushes the side (and the rim the wall)
        assert serial[-1][column] > 0.1, column
    for p, s in common:  # the same load; increments cut on one side only add rows
        for column in COLUMNS:  # forces ~1 N, Newton's tolerance 1e-9 relative
            if s[column] is None:  # no contact yet: no force centre
                assert p[column] is None, column
            else:
                assert p[column] == pytest.approx(s[column], rel=1e-6, abs=1e-9), column
