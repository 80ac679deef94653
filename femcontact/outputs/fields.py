"""Field output of a finished simulation: `fields.npz` for pictures, XDMF for ParaView.

fields.npz (gathered on rank 0; nodes on partition boundaries appear once per rank):
points (N x 3, reference coordinates of P1 nodes, mm), cells (M x k), cell_type,
displacement (N x 3, mm), von_mises (M, MPa, cellwise), rigid_outline (P x 3, final pose),
and the effects' cell fields (M, cellwise), e.g. `peeq` (equivalent plastic strain) with `plasticity`.
"""
from pathlib import Path

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from femcontact.errors import InputError
from femcontact.io import write_npz_atomic
from femcontact.physics.signed_distance import outline


def _p1_fields(simulation):
    """Displacement (P1) and the cellwise fields (DG0): von_mises, then the effects' own."""
    p = simulation.problem
    V1 = fem.VectorFunctionSpace(p.mesh, ("Lagrange", 1))
    u1 = fem.Function(V1, name="displacement")
    u1.interpolate(p.u)
    W0 = fem.FunctionSpace(p.mesh, ("DG", 0))
    values = {"von_mises": p.von_mises}
    for component in p.components:
        values.update(component.cell_fields())
    cellwise = []
    for name, value in values.items():
        field = fem.Function(W0, name=name)
        field.interpolate(fem.Expression(value, W0.element.interpolation_points()))
        cellwise.append(field)
    return u1, cellwise


def write_fields(simulation, case_dir: Path) -> None:
    p = simulation.problem
    comm = p.mesh.comm
    u1, cellwise = _p1_fields(simulation)
    V1 = u1.function_space
    tdim = p.mesh.topology.dim
    n_cells = p.mesh.topology.index_map(tdim).size_local
    points = V1.tabulate_dof_coordinates()
    cells = V1.dofmap.list.array.reshape(n_cells + p.mesh.topology.index_map(tdim).num_ghosts, -1)[:n_cells]
    displacement = np.zeros((len(points), 3))
    displacement[:, : p.dim] = u1.x.array.reshape(-1, p.dim)
    local = (points, cells, displacement, {f.name: f.x.array[:n_cells].copy() for f in cellwise})
    gathered = comm.gather(local, root=0)
    error = None
    if comm.rank == 0:
        try:
            _write_npz(p, gathered, case_dir)
        except InputError as failure:  # a WriteError: every rank stops, none waits below
            error = failure
    error = comm.bcast(error, root=0)
    if error is not None:
        raise error
    if p.scene["outputs"]["fields"]:
        from dolfinx.io import XDMFFile

        with XDMFFile(comm, str(Path(case_dir) / "fields.xdmf"), "w") as xdmf:
            xdmf.write_mesh(p.mesh)
            xdmf.write_function(u1)
            for field in cellwise:
                xdmf.write_function(field)
    comm.barrier()


def _write_npz(p, gathered, case_dir: Path) -> None:
    """fields.npz from the gathered (points, cells, displacement, cell fields) of every rank (rank 0)."""
    offsets = np.cumsum([0] + [len(g[0]) for g in gathered])
    rigid = p.rigid
    shape_outline = outline(p.model.rigid)
    if len(shape_outline):
        from femcontact.physics.signed_distance import reference_point

        local_points = shape_outline[:, : p.dim] + reference_point(p.model.rigid)
        placed = np.array([rigid.place(point) for point in local_points])
        shape_outline = np.c_[placed, np.zeros((len(placed), 3 - p.dim))]
    write_npz_atomic(
        Path(case_dir) / "fields.npz",
        points=np.vstack([g[0] for g in gathered]),
        cells=np.vstack([g[1] + offset for g, offset in zip(gathered, offsets)]),
        cell_type="triangle" if p.dim == 2 else "tetra",
        displacement=np.vstack([g[2] for g in gathered]),
        **{name: np.concatenate([g[3][name] for g in gathered]) for name in gathered[0][3]},
        rigid_outline=shape_outline,
        named_point_names=np.array(list(p.model.points)),
        named_point_coords=np.array([np.r_[x, np.zeros(3 - p.dim)] for x in p.model.points.values()]),
    )
