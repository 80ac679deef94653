"""The contact update on 2 ranks: MUMPS reads a sparse right-hand side and the entries of the
inverse it is asked for on rank 0 alone, so every dof must reach it whichever rank owns it, and
the solves after the entries of the inverse must hold."""
import pytest
from mpi4py import MPI

from tests.unit.test_linear import update_error

pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("by_entries", [False, True])
def test_update_holds_the_dense_solves_on_two_ranks(by_entries):
    assert MPI.COMM_WORLD.size == 2
    assert update_error(MPI.COMM_WORLD, by_entries) <= 1e-12
