"""The 3-D Hertz quarter model gives the same answer on 2 ranks as on 1 (run under mpirun -n 2),
and its supports balance the load: the bottom reaction is P/4 = 500 N along z to the residual
tolerance (the symmetry planes hold only their normal displacement, so they take no z force).
With quadratic elements the pressures recovered at the nodes give the same a and p0 too."""
import pytest
from mpi4py import MPI

from femcontact.references.hertz import benchmark_radius_3d
from femcontact.families.hertz import benchmark as hertz
from femcontact.solver.stepping import Simulation


def run(comm, degree: int = 1) -> dict:
    simulation = Simulation(hertz.scene_3d(benchmark_radius_3d() / 2.5, degree=degree), comm)
    simulation.run()
    return {**simulation.step_end_rows()["press"], **hertz.measure(simulation), "dofs": simulation.dofs}


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_match_one_rank():
    parallel = run(MPI.COMM_WORLD)
    serial = run(MPI.COMM_SELF)
    assert parallel["dofs"] == serial["dofs"]
    for key in ("a", "p0", "rigid_z", "reaction_bottom_z", "contact_top_Fz"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-6), key
    assert serial["reaction_bottom_z"] == pytest.approx(500.0, rel=1e-6)


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_quadratic_pressures_recovered_on_two_ranks_match_one_rank():
    parallel, serial = run(MPI.COMM_WORLD, degree=2), run(MPI.COMM_SELF, degree=2)
    for key in ("a", "p0", "contact_nodes"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-6), key
