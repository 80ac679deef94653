"""Field output: `fields.npz` (the final state, for pictures) and, with `outputs.fields`, a
ParaView time series of every converged increment (`FieldSeries`).

fields.npz (gathered on rank 0; nodes on partition boundaries appear once per rank):
points (N x 3, reference coordinates of P1 nodes, mm), cells (M x k), cell_type,
displacement (N x 3, mm), von_mises (M, MPa, cellwise), rigid_outline (P x 3, final pose),
and the effects' cell fields (M, cellwise), e.g. `peeq` (equivalent plastic strain) with `plasticity`.

The time series (femcontact.outputs.xdmf), one frame per converged increment (every
`outputs.every`-th, and the last of each step), at the scene's time (s):
fields.xdmf on the deformable body's P1 nodes and cells, in its reference configuration:
  displacement (mm, node), von_mises (MPa, cell), stress (MPa, cell, 3 x 3: Cauchy, or first
  Piola-Kirchhoff with large_strain; in 2-D the in-plane components, zz left 0),
  contact_pressure (MPa), tangential_traction (MPa, vector), contact_status (0 open, 1 stick,
  2 slip, as Abaqus' CSTATUS; touching without friction is 2), slip (mm, a touching node's
  tangential motion relative to the rigid body since the step began; 0 where open), gap (mm, signed distance to the rigid body),
  all per node: contact values are lumped on the contact surface's nodes and 0 elsewhere;
rigid.xdmf: the rigid body's outline (2-D, lines) or surface (3-D, triangles) in its initial
  pose, with its `displacement` (mm) per frame: warp both files by `displacement` (ParaView's
  Warp By Vector) and the bodies move together.
The effects' cell fields (e.g. `peeq`) are in every frame of fields.xdmf too.
"""
from pathlib import Path

import numpy as np
from dolfinx import fem

from femcontact.errors import InputError
from femcontact.io import write_npz_atomic
from femcontact.physics.signed_distance import outline, reference_point, surface


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
    comm.barrier()


def _effect_cell_fields(p, space) -> list:
    """(name, space, UFL value) of each effect's cell fields (e.g. plasticity's peeq)."""
    return [(name, space, value) for component in p.components for name, value in component.cell_fields().items()]


def _write_npz(p, gathered, case_dir: Path) -> None:
    """fields.npz from the gathered (points, cells, displacement, cell fields) of every rank (rank 0)."""
    offsets = np.cumsum([0] + [len(g[0]) for g in gathered])
    rigid = p.rigid
    shape_outline = outline(p.model.rigid)
    if len(shape_outline):
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


class FieldSeries:
    """A listener (row, cuts) of a Simulation writing fields.xdmf and rigid.xdmf frame by frame
    (see the module's docstring). Built on every rank after the simulation (and any restart);
    rank 0 writes. A failed write stops the writing and is kept in `error` (a WriteError) for
    the caller to raise once the ranks are in step."""

    def __init__(self, simulation, case_dir: Path):
        import ufl

        p = self.problem = simulation.problem
        self.comm, self.dim, self.error = p.mesh.comm, p.dim, None
        every, steps = p.scene["outputs"]["every"], p.scene["steps"]
        self.every, self.increments = every, 0
        self.step_ends = dict(zip([step["name"] for step in steps], np.cumsum([step["duration"] for step in steps])))
        self.V1 = fem.VectorFunctionSpace(p.mesh, ("Lagrange", 1))
        self.u1 = fem.Function(self.V1)
        tdim = p.mesh.topology.dim
        self.n_cells = p.mesh.topology.index_map(tdim).size_local
        W0 = fem.FunctionSpace(p.mesh, ("DG", 0))
        T0 = fem.TensorFunctionSpace(p.mesh, ("DG", 0))
        self.cellwise = {name: (fem.Function(space), fem.Expression(value, space.element.interpolation_points()))
                         for name, space, value in (("von_mises", W0, p.von_mises), ("stress", T0, p.stress),
                                                    *_effect_cell_fields(p, W0))}
        self.cell_dofs = W0.dofmap.list.array[: self.n_cells]  # one (block) dof per cell, for W0 and T0 alike
        # contact values lumped to the P1 nodes of the contact surface: integral of value * phi over area
        contact, dim = p.contact, p.dim
        traction, normal = p.traction, contact.normal
        tangential = traction - ufl.dot(traction, normal) * normal
        friction = [component for component in p.components if component.name == "friction"]
        stick_slip = list(friction[0].nodal_outputs().values()) if friction else [0.0, 0.0]
        values = [contact.pressure, contact.gap, *stick_slip, *[tangential[k] for k in range(dim)],
                  *[contact.xi[k] for k in range(dim)], *[contact.normal_local[k] for k in range(dim)], 1.0]
        self.friction = bool(friction)
        self.Q = fem.VectorFunctionSpace(p.mesh, ("Lagrange", 1), dim=len(values))
        q = ufl.TestFunction(self.Q)
        self.nodal_form = fem.form(sum(value * q[i] for i, value in enumerate(values)) * p.ds_contact)
        self.nodal = fem.Function(self.Q)
        index_map = self.V1.dofmap.index_map
        self.n_owned = index_map.size_local
        global_nodes = index_map.local_to_global(np.arange(self.n_owned, dtype=np.int32))
        cells = index_map.local_to_global(self.V1.dofmap.list.array).reshape(-1, tdim + 1)[: self.n_cells]
        points = self.V1.tabulate_dof_coordinates()[: self.n_owned]
        self.order = self.comm.gather(global_nodes, root=0)
        gathered = self.comm.gather((points, cells), root=0)
        self.step, self.step_start = None, None
        self.xi = self._contact_values()["xi"]  # the state the first step starts from
        self.contact = None
        simulation.recorder.observers.append(self.capture)
        self.deformable = self.rigid = None
        if self.comm.rank == 0:
            from femcontact.outputs.xdmf import XdmfSeries

            try:
                nodes = np.concatenate(self.order)
                self.deformable = XdmfSeries(Path(case_dir) / "fields.xdmf", self._by_node(nodes, [g[0] for g in gathered]),
                                             np.vstack([g[1] for g in gathered]), "triangle" if dim == 2 else "tetra")
                rigid = _rigid_mesh(p)
                if rigid is not None:
                    self.rigid_points = rigid[0]
                    self.rigid = XdmfSeries(Path(case_dir) / "rigid.xdmf", *rigid)
            except InputError as failure:
                self.error = failure

    def _by_node(self, nodes, parts) -> np.ndarray:
        """Rows of the ranks' owned nodes (in gather order) placed at their global node numbers."""
        values = np.concatenate(parts)
        out = np.zeros((len(nodes), *values.shape[1:]))
        out[nodes] = values
        return out

    def _contact_values(self) -> dict:
        """This rank's owned nodes: lumped contact values, the local position xi and normal."""
        from femcontact.outputs.recorder import assemble_nodal

        assemble_nodal(self.nodal, self.nodal_form)
        k = self.Q.dofmap.index_map_bs
        values = self.nodal.x.array[: self.n_owned * k].reshape(-1, k)
        area = values[:, -1:]
        lumped = np.where(area > 0, values / np.where(area > 0, area, 1.0), 0.0)
        pressure, gap, stick, slip = lumped[:, :4].T
        tangential, xi, normal = np.split(lumped[:, 4:-1], 3, axis=1)
        # touching: a positive lumped pressure (with quadratic elements or in 3-D the contact is integrated at
        # Gauss points, so a node at the edge of the contact zone may be touched on a part of its patch only)
        status = np.where(pressure > 0, np.where(self.friction & (stick > slip), 1.0, 2.0), 0.0)
        normal = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        return {"contact_pressure": pressure, "gap": gap, "contact_status": status,
                "tangential_traction": _pad(tangential), "xi": xi, "normal": normal}

    def capture(self) -> None:
        """The contact values of a converged increment, read before it is committed (committing
        moves the friction anchors, which would blur the stick/slip states)."""
        self.contact = self._contact_values()

    def __call__(self, row: dict, cuts: int = 0) -> None:
        contact = self.contact
        if row["step"] != self.step:  # slip is measured from the state the step began in
            self.step, self.step_start = row["step"], self.xi
        self.xi = contact["xi"]
        self.increments += 1
        end = abs(row["time"] - self.step_ends.get(row["step"], np.inf)) <= 1e-9 * max(1.0, abs(row["time"]))
        if self.increments % self.every and not end:
            return
        change = contact["xi"] - self.step_start
        change -= np.sum(change * contact["normal"], axis=1, keepdims=True) * contact["normal"]
        slip = np.where(contact["contact_status"] > 0, np.linalg.norm(change, axis=1), 0.0)
        self.u1.interpolate(self.problem.u)
        nodal = {"displacement": _pad(self.u1.x.array[: self.n_owned * self.dim].reshape(-1, self.dim)),
                 **{name: contact[name] for name in ("contact_pressure", "tangential_traction", "contact_status")},
                 "slip": slip, "gap": contact["gap"]}
        cellwise = {}
        for name, (function, expression) in self.cellwise.items():
            function.interpolate(expression)
            size = function.function_space.dofmap.index_map_bs
            values = function.x.array.reshape(-1, size)[self.cell_dofs]
            cellwise[name] = _pad_tensor(values, self.dim) if name == "stress" else values
        gathered = self.comm.gather((nodal, cellwise), root=0)
        if self.comm.rank != 0 or self.error is not None:
            return
        nodes = np.concatenate(self.order)
        point_data = {name: self._by_node(nodes, [g[0][name] for g in gathered]) for name in nodal}
        cell_data = {name: np.concatenate([g[1][name] for g in gathered]) for name in cellwise}
        try:
            self.deformable.add(row["time"], point_data, cell_data)
            if self.rigid is not None:
                self.rigid.add(row["time"], {"displacement": _rigid_displacement(self.problem.rigid, self.rigid_points)},
                               {})
        except InputError as failure:
            self.error = failure


def _pad(vectors: np.ndarray) -> np.ndarray:
    """N x dim vectors as N x 3 (z = 0 in 2-D)."""
    return np.c_[vectors, np.zeros((len(vectors), 3 - vectors.shape[1]))]


def _pad_tensor(values: np.ndarray, dim: int) -> np.ndarray:
    """N x dim^2 tensors (row-major) as N x 9."""
    out = np.zeros((len(values), 3, 3))
    out[:, :dim, :dim] = values.reshape(-1, dim, dim)
    return out.reshape(-1, 9)


def _rigid_mesh(p):
    """(points N x 3 in the initial pose, cells, cell type) of the rigid body's outline (2-D) or
    surface (3-D), or None for a shape without one."""
    rigid = p.model.rigid
    if p.dim == 2:
        local = outline(rigid)
        cells = np.c_[np.arange(len(local) - 1), np.arange(1, len(local))]
        kind = "line"
    else:
        local, cells = surface(rigid)
        kind = "triangle"
    if not len(local):
        return None
    initial = np.zeros(len(p.rigid.values))
    placed = np.array([p.rigid.place(point[: p.dim] + reference_point(rigid), initial) for point in local])
    return _pad(placed), cells, kind


def _rigid_displacement(rigid, points: np.ndarray) -> np.ndarray:
    """Displacement (mm) of the rigid body's points `points` (N x 3, initial pose) in its pose now:
    translation plus the rotation about the reference point p0."""
    from femcontact.physics.rotation import rotation_numpy

    dim = rigid.dim
    translation, angles = rigid.split(rigid.values)
    x = points[:, :dim] - rigid.p0
    moved = np.asarray(translation) + x @ (rotation_numpy(angles) - np.eye(dim)).T
    return _pad(moved)
