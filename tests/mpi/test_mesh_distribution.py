"""The gmsh model built on rank 0 is distributed: run with `mpirun -n 2 python -m pytest tests/mpi`."""
import numpy as np
import pytest
from dolfinx.mesh import compute_midpoints
from mpi4py import MPI

from femcontact.families import resolve_scene
from geometry import measures
from geometry.model import build

pytestmark = pytest.mark.mpi

SCENE = {"dim": 2, "geometry": "peg_in_hole", "peg": {"width": 40, "length": 10, "insertion_depth": 5},
         "hole": {"width": 40.1, "kind": "single", "chamfer_width": 1.0}, "steps": [{"name": "load"}]}


@pytest.mark.parametrize("dim", [2, 3])
def test_mesh_is_distributed(dim):
    world = MPI.COMM_WORLD
    scene = resolve_scene({**SCENE, "dim": dim, "mesh": {"resolution": 1.0 if dim == 2 else 0.3}})
    model = build(scene, world)
    serial = build(scene, MPI.COMM_SELF)  # the same mesh, whole on every rank
    tdim = model.mesh.topology.dim
    owned = model.mesh.topology.index_map(tdim).size_local
    assert owned > 0
    assert world.allreduce(owned) == serial.mesh.topology.index_map(tdim).size_local
    assert owned < serial.mesh.topology.index_map(tdim).size_local  # each rank holds a part
    assert measures.measure(model) == pytest.approx(measures.measure(serial), rel=1e-12)
    assert model.facets == serial.facets and model.cells == serial.cells
    for name in model.facets:
        assert measures.measure(model, facet=name) == pytest.approx(measures.measure(serial, facet=name), rel=1e-12)
    for name in model.cells:
        assert measures.measure(model, cell=name) == pytest.approx(measures.measure(serial, cell=name), rel=1e-12)


def test_the_partition_is_the_same_every_time():
    """SCOTCH partitions the mesh with one thread (`geometry.model.build`): with several, the cells
    each rank owns changed from run to run, and with them the order of every parallel sum."""
    scene = resolve_scene({**SCENE, "dim": 3, "mesh": {"resolution": 0.35}})
    owned = []
    for _ in range(8):
        mesh = build(scene, MPI.COMM_WORLD).mesh
        tdim = mesh.topology.dim
        cells = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
        owned.append(np.round(compute_midpoints(mesh, tdim, cells), 9))
    for other in owned[1:]:
        assert other.shape == owned[0].shape and np.array_equal(other, owned[0])
