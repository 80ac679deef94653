"""The contact update's columns on 2 ranks: MUMPS reads a sparse right-hand side on rank 0 alone,
so every unit vector must reach it whichever rank owns its dof."""
import pytest
from mpi4py import MPI

from tests.unit.test_linear import unit_columns_error

pytestmark = pytest.mark.mpi


def test_unit_columns_are_the_dense_solves_on_two_ranks():
    assert MPI.COMM_WORLD.size == 2
    assert unit_columns_error(MPI.COMM_WORLD) <= 1e-12
