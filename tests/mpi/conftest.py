"""Under mpirun, a test failing on one rank would leave the other waiting in a collective
call forever: abort the whole MPI job instead, so the run ends with a failure."""
import pytest
from mpi4py import MPI


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.failed and MPI.COMM_WORLD.size > 1:
        print(f"\n[rank {MPI.COMM_WORLD.rank}] {item.nodeid} failed:\n{report.longreprtext}", flush=True)
        MPI.COMM_WORLD.Abort(1)
