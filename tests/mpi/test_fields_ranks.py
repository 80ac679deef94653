"""The field output does not depend on the number of ranks (run under mpirun -n 2): the wedging
scene written on both ranks together and on rank 0 alone gives the same ParaView frames and the
same fields.npz, node for node (matched by coordinates), to the solver tolerance."""
import tempfile
from pathlib import Path

import meshio
import numpy as np
import pytest
from mpi4py import MPI

from femcontact.families import resolve_scene
from femcontact.io import make_dir
from femcontact.outputs.fields import Fields, FieldSeries, write_fields
from femcontact.solver.stepping import Simulation

SCENE = {
    "name": "ranks", "dim": 2, "geometry": "peg_in_hole", "effects": ["friction", "plane_strain"],
    "peg": {"width": 40.0, "length": 10.0, "insertion_depth": 5.0}, "hole": {"width": 40.1},
    "contact": {"mu": 0.2}, "mesh": {"resolution": 0.5}, "outputs": {"fields": True},
    "steps": [{"name": "load", "increments": 2, "force": [-5.0, 1.0]}, {"name": "release", "increments": 2}],
}


def write(comm, directory: Path) -> None:
    simulation = Simulation(resolve_scene(SCENE), comm)
    simulation.listeners.append(FieldSeries(simulation, directory))
    simulation.run()


def frames(path: Path):
    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        order = np.lexsort(points.T[::-1])
        data = [reader.read_data(k) for k in range(reader.num_steps)]
    return points[order], [(t, {name: values[order] for name, values in nodal.items()}) for t, nodal, _ in data]


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_write_the_series_of_one():
    root = Path(MPI.COMM_WORLD.bcast(tempfile.mkdtemp() if MPI.COMM_WORLD.rank == 0 else None))
    write(MPI.COMM_WORLD, root / "parallel")
    if MPI.COMM_WORLD.rank == 0:
        write(MPI.COMM_SELF, root / "serial")
        points, parallel = frames(root / "parallel" / "fields.xdmf")
        serial_points, serial = frames(root / "serial" / "fields.xdmf")
        assert np.array_equal(points, serial_points)  # each node once, whatever the partition
        assert len(parallel) == len(serial) == 4
        for (t, one), (t_serial, other) in zip(parallel, serial):
            assert t == t_serial
            for name in ("displacement", "contact_pressure", "contact_status", "slip"):
                scale = max(np.abs(other[name]).max(), 1e-12)
                assert np.abs(one[name] - other[name]).max() / scale < 1e-6, (t, name)
    MPI.COMM_WORLD.barrier()


def write_final(comm, directory: Path) -> dict:
    """fields.npz of the wedged peg (tests/support/wedged_fields.py) run on `comm`; its last history row."""
    from wedged_fields import WEDGED, WEDGING_SCENE

    from femcontact.api import load_scene

    simulation = Simulation(load_scene(WEDGING_SCENE, WEDGED), comm)
    fields = Fields(simulation)
    simulation.run()
    write_fields(simulation, directory, fields)
    return simulation.history[-1]


@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="run with mpirun -n 2")
def test_two_ranks_write_the_final_fields_of_one():
    """fields.npz on two ranks: each node once, the contact fields those of one rank node for node
    (to the solver's tolerance), integrating to the zones' contact forces as on one rank."""
    from wedged_fields import contact_forces, read_fields

    root = Path(MPI.COMM_WORLD.bcast(tempfile.mkdtemp() if MPI.COMM_WORLD.rank == 0 else None))
    row = write_final(MPI.COMM_WORLD, make_dir(root / "parallel"))
    if MPI.COMM_WORLD.rank == 0:
        write_final(MPI.COMM_SELF, make_dir(root / "serial"))
        parallel, serial = (read_fields(root / name / "fields.npz") for name in ("parallel", "serial"))
        order, serial_order = (np.lexsort(f["points"].T[::-1]) for f in (parallel, serial))
        assert np.array_equal(parallel["points"][order], serial["points"][serial_order])
        for name in ("contact_pressure", "tangential_traction", "contact_status", "slip", "gap", "contact_area"):
            one, other = parallel[name][order], serial[name][serial_order]
            assert np.abs(one - other).max() <= 1e-6 * max(np.abs(other).max(), 1e-12), name
        for zone, (force, touching) in contact_forces(parallel).items():
            assert touching >= 1 and force == pytest.approx(row[f"contact_{zone}_force"], rel=1e-9)
    MPI.COMM_WORLD.barrier()
