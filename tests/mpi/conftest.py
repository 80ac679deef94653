"""These tests compare a distributed run with a serial one: they need `mpirun -n 2`
(`make test-mpi`); under a single process they are skipped, since they could not fail.
Under mpirun, a test failing on one rank would leave the other waiting in a collective
call forever: abort the whole MPI job instead, so the run ends with a failure."""
from pathlib import Path

import pytest
from mpi4py import MPI


def pytest_collection_modifyitems(config, items):
    here = Path(__file__).parent
    if MPI.COMM_WORLD.size < 2:
        for item in items:
            if here in Path(item.fspath).parents:
                item.add_marker(pytest.mark.skip(reason="needs mpirun -n 2 (make test-mpi)"))


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.failed and MPI.COMM_WORLD.size > 1:
        print(f"\n[rank {MPI.COMM_WORLD.rank}] {item.nodeid} failed:\n{report.longreprtext}", flush=True)
        MPI.COMM_WORLD.Abort(1)
