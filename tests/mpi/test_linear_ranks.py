"""The contact update on 2 ranks: MUMPS reads a sparse right-hand side and the entries of the
inverse it is asked for on rank 0 alone, so every dof must reach it whichever rank owns it, and
the solves after the entries of the inverse must hold. Entries of few columns are whole unit
columns on 2 ranks (`PARALLEL_ENTRIES_FROM`): both ways are checked."""
import pytest
from mpi4py import MPI

from femcontact.solver import linear
from tests.unit.test_linear import update_error

pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("by_entries, entries_from", [(False, None), (True, 0), (True, 10**9)])
def test_update_holds_the_dense_solves_on_two_ranks(by_entries, entries_from, monkeypatch):
    assert MPI.COMM_WORLD.size == 2
    if entries_from is not None:  # 0: always MUMPS's entries; 10**9: always whole columns
        monkeypatch.setattr(linear, "PARALLEL_ENTRIES_FROM", entries_from)
    assert update_error(MPI.COMM_WORLD, by_entries) <= 1e-12
