"""Field output: `fields.npz` (the final state, for pictures and scripts) and, with
`outputs.fields`, a ParaView time series of every converged increment (`FieldSeries`). Both
hold the same fields (`Fields`), gathered on rank 0, each node and each cell once whatever the
number of ranks:

on the deformable body's P1 nodes and cells, in its reference configuration:
  displacement (mm, node), von_mises (MPa, cell), stress (MPa, cell, 3 x 3: Cauchy, or first
  Piola-Kirchhoff with large_strain; in 2-D the in-plane components, zz left 0),
  contact_pressure (MPa), tangential_traction (MPa, vector), contact_status (0 open, 1 stick,
  2 slip, as Abaqus' CSTATUS; touching without friction is 2), slip (mm, a touching node's
  tangential motion relative to the rigid body since the step began; 0 where open), gap (mm, signed distance to the rigid body),
  all per node: contact values are lumped on the contact surface's nodes (integral of the value
  times the node's hat function over the contact surface, divided by the integral of the hat
  function: the node's area; a point force, a sharp rigid corner's, is shared between the two
  nodes of the facet it presses as their hat functions share it) and 0 elsewhere; a node sticks
  where most of its contact force sticks;
  the effects' cell fields (M, cellwise), e.g. `peeq` (equivalent plastic strain) with `plasticity`.

fields.npz: those arrays (vectors N x 3, zero-padded in 2-D; stress M x 9) of the last converged
increment, and points (N x 3, mm), cells (M x k), cell_type, contact_area (N, mm^2 in 3-D, mm
per unit thickness in 2-D: the node's area, 0 off the contact surface), rigid_outline (P x 3,
final pose), named_point_names, named_point_coords. A state restored without its increment (the
dislodging family's snapshots) has slip 0 and its stick/slip status from the committed anchors.

The time series (femcontact.outputs.xdmf), one frame per converged increment (every
`outputs.every`-th, and the last of each step), at the scene's time (s):
fields.xdmf: the fields above;
rigid.xdmf: the rigid body's outline (2-D, lines) or surface (3-D, triangles) in its initial
  pose, with its `displacement` (mm) per frame: warp both files by `displacement` (ParaView's
  Warp By Vector) and the bodies move together.
"""
from pathlib import Path

import numpy as np
from dolfinx import fem

from femcontact.errors import InputError
from femcontact.io import write_npz_atomic
from femcontact.physics.signed_distance import outline, reference_point, surface

CONTACT_FIELDS = ("contact_pressure", "tangential_traction", "contact_status", "slip", "gap")


class Fields:
    """The fields of a simulation's state (see the module's docstring), built on every rank.
    With `follow` it watches the converged increments (a recorder observer and a listener of the
    simulation, in that order, until `detach`): their contact values are those of the increment
    before it is committed (committing moves the friction anchors, which would blur the stick/slip
    states) and slip is measured from the state the step began in (from the state it was built in
    for the first step it sees). Watching keeps a copy of the last two increments' states
    (`Problem.state`, before their commit); their contact values are assembled only when an
    output asks for them (a frame, the start of a step's slip, the final state)."""

    def __init__(self, simulation, follow: bool = True):
        import ufl

        p = self.problem = simulation.problem
        self.comm, self.dim = p.mesh.comm, p.dim
        self.V1 = fem.VectorFunctionSpace(p.mesh, ("Lagrange", 1))
        self.u1 = fem.Function(self.V1)
        tdim = p.mesh.topology.dim
        self.n_cells = p.mesh.topology.index_map(tdim).size_local
        W0 = fem.FunctionSpace(p.mesh, ("DG", 0))
        T0 = fem.TensorFunctionSpace(p.mesh, ("DG", 0))
        effect_fields = [(name, W0, value) for component in p.components
                         for name, value in component.cell_fields().items()]
        self.cellwise = {name: (fem.Function(space), fem.Expression(value, space.element.interpolation_points()))
                         for name, space, value in (("von_mises", W0, p.von_mises), ("stress", T0, p.stress),
                                                    *effect_fields)}
        self.cell_dofs = W0.dofmap.list.array[: self.n_cells]  # one (block) dof per cell, for W0 and T0 alike
        # contact values lumped to the P1 nodes of the contact surface: integral of value * phi over area
        contact, dim = p.contact, p.dim
        traction, normal = p.traction, contact.normal
        tangential = traction - ufl.dot(traction, normal) * normal
        friction = [component for component in p.components if component.name == "friction"]
        # stick and slip weighted by the pressure: a node sticks where most of its contact force sticks
        stick_slip = [contact.pressure * value for value in friction[0].nodal_outputs().values()] if friction \
            else [0.0, 0.0]
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
        order = self.comm.gather(global_nodes, root=0)
        gathered = self.comm.gather((points, cells), root=0)
        self.nodes = self.points = self.cells = None  # rank 0: the gathered mesh
        if self.comm.rank == 0:
            self.nodes = np.concatenate(order)
            self.points = self._by_node([g[0] for g in gathered])
            self.cells = np.vstack([g[1] for g in gathered])
        self.cell_type = "triangle" if dim == 2 else "tetra"
        self.step, self.increments = None, []  # [state before its commit, its contact values once read]
        self.step_start = self._contact_values()["xi"]
        self.simulation = simulation if follow else None
        if follow:
            simulation.recorder.observers.append(self.capture)
            simulation.listeners.append(self)

    def detach(self) -> None:
        """Stop watching the simulation's increments."""
        if self.simulation is not None:
            self.simulation.recorder.observers.remove(self.capture)
            self.simulation.listeners.remove(self)
            self.simulation = None

    def _by_node(self, parts) -> np.ndarray:
        """Rows of the ranks' owned nodes (in gather order) placed at their global node numbers (rank 0)."""
        values = np.concatenate(parts)
        out = np.zeros((len(self.nodes), *values.shape[1:]))
        out[self.nodes] = values
        return out

    def _contact_values(self) -> dict:
        """This rank's owned nodes: lumped contact values, the local position xi and normal, the area."""
        from femcontact.outputs.recorder import assemble_nodal

        assemble_nodal(self.nodal, self.nodal_form, self._add_point_contacts)
        k = self.Q.dofmap.index_map_bs
        values = self.nodal.x.array[: self.n_owned * k].reshape(-1, k)
        area = values[:, -1:]
        lumped = np.where(area > 0, values / np.where(area > 0, area, 1.0), 0.0)
        pressure, gap, stick, slip = lumped[:, :4].T
        tangential, xi, normal = np.split(lumped[:, 4:-1], 3, axis=1)
        # touching: a positive lumped pressure (the lumped value averages the node's patch, so a node
        # at the edge of the contact zone may be touched on a part of its patch only)
        status = np.where(pressure > 0, np.where(self.friction & (stick > slip), 1.0, 2.0), 0.0)
        normal = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        return {"contact_pressure": pressure, "gap": gap, "contact_status": status,
                "tangential_traction": _pad(tangential), "xi": xi, "normal": normal, "contact_area": area[:, 0]}

    def _add_point_contacts(self, array: np.ndarray) -> None:
        """The effects' point forces (a sharp rigid corner's) added to the nodal integrals of the
        local array: a force F at s along the facet a-b adds (1 - s) F to node a and s F to node b,
        as the integral of a point load times the nodes' hat functions; its normal part to the
        pressure and to the stick or the slip weight, its tangential part to the traction."""
        k, dim = self.Q.dofmap.index_map_bs, self.dim
        rows = array.reshape(-1, k)
        for component in self.problem.components:
            for a, b, s, f_n, f_t, stick in component.point_contacts():
                for node, share in ((a, 1 - s), (b, s)):
                    rows[node, 0] += share * f_n
                    rows[node, 2 if stick else 3] += share * f_n
                    rows[node, 4: 4 + dim] += share * np.asarray(f_t)

    def capture(self) -> None:
        """A converged increment, before it is committed: its state kept, its contact values unread."""
        self.increments = self.increments[-1:] + [[self.problem.state(), None]]

    def _increment_contact(self, increment: list) -> dict:
        """The contact values of a watched increment, assembled in its state before its commit
        (restored for the assembly, the state now restored after it) on first request."""
        if increment[1] is None:
            now = self.problem.state()
            self.problem.restore(increment[0])
            try:
                increment[1] = self._contact_values()
            finally:
                self.problem.restore(now)
        return increment[1]

    def __call__(self, row: dict, cuts: int = 0) -> None:
        """A converged increment recorded: the first of a step sets slip's origin, the step's start."""
        if not self.increments:  # a row computed before it watched (a checkpoint's)
            return
        if row["step"] != self.step:  # slip is measured from the state the step began in: the last increment's
            self.step = row["step"]
            if len(self.increments) > 1:
                self.step_start = self._increment_contact(self.increments[0])["xi"]

    def _nodal_contact(self) -> dict:
        """The contact fields of this rank's owned nodes in the state now: those of its increment
        when it is the last one recorded, else read from the state (slip 0)."""
        latest = self.simulation is not None and self.increments
        contact = self._increment_contact(self.increments[-1]) if latest else self._contact_values()
        start = self.step_start if latest else contact["xi"]
        change = contact["xi"] - start
        change -= np.sum(change * contact["normal"], axis=1, keepdims=True) * contact["normal"]
        slip = np.where(contact["contact_status"] > 0, np.linalg.norm(change, axis=1), 0.0)
        return {**{name: contact[name] for name in CONTACT_FIELDS if name != "slip"}, "slip": slip,
                "contact_area": contact["contact_area"]}

    def gather(self):
        """(point data, cell data) of the state now on rank 0, None on the other ranks."""
        self.u1.interpolate(self.problem.u)
        nodal = {"displacement": _pad(self.u1.x.array[: self.n_owned * self.dim].reshape(-1, self.dim)),
                 **self._nodal_contact()}
        cellwise = {}
        for name, (function, expression) in self.cellwise.items():
            function.interpolate(expression)
            size = function.function_space.dofmap.index_map_bs
            values = function.x.array.reshape(-1, size)[self.cell_dofs]
            cellwise[name] = _pad_tensor(values, self.dim) if name == "stress" else values[:, 0]
        gathered = self.comm.gather((nodal, cellwise), root=0)
        if self.comm.rank != 0:
            return None
        point_data = {name: self._by_node([g[0][name] for g in gathered]) for name in nodal}
        cell_data = {name: np.concatenate([g[1][name] for g in gathered]) for name in cellwise}
        return point_data, cell_data


def write_fields(simulation, case_dir: Path, fields: Fields | None = None) -> None:
    """fields.npz of the simulation's state in case_dir; `fields`: the Fields that followed its
    increments (else one built now, which reads the contact values from the state)."""
    fields = fields or Fields(simulation, follow=False)
    frame = fields.gather()
    error = None
    if frame is not None:
        try:
            _write_npz(fields, *frame, case_dir)
        except InputError as failure:  # a WriteError: every rank stops, none waits below
            error = failure
    error = fields.comm.bcast(error, root=0)
    if error is not None:
        raise error


def _write_npz(fields: Fields, point_data: dict, cell_data: dict, case_dir: Path) -> None:
    """fields.npz from a gathered frame (rank 0)."""
    p = fields.problem
    shape_outline = outline(p.model.rigid)
    if len(shape_outline):
        local_points = shape_outline[:, : p.dim] + reference_point(p.model.rigid)
        placed = np.array([p.rigid.place(point) for point in local_points])
        shape_outline = _pad(placed)
    write_npz_atomic(
        Path(case_dir) / "fields.npz", points=fields.points, cells=fields.cells, cell_type=fields.cell_type,
        **point_data, **cell_data, rigid_outline=shape_outline,
        named_point_names=np.array(list(p.model.points)),
        named_point_coords=np.array([np.r_[x, np.zeros(3 - p.dim)] for x in p.model.points.values()]),
    )


class FieldSeries:
    """A listener (row, cuts) of a Simulation writing fields.xdmf and rigid.xdmf frame by frame
    (see the module's docstring). Built on every rank after the simulation (and any restart),
    on `fields` (a following Fields; else it builds one, which `detach` stops); rank 0 writes. A
    failed write stops the writing and is kept in `error` (a WriteError) for the caller to raise
    once the ranks are in step."""

    def __init__(self, simulation, case_dir: Path, fields: Fields | None = None):
        p = self.problem = simulation.problem
        self.fields = fields or Fields(simulation)
        self.error = None
        every, steps = p.scene["outputs"]["every"], p.scene["steps"]
        self.every, self.increments = every, 0
        self.step_ends = dict(zip([step["name"] for step in steps], np.cumsum([step["duration"] for step in steps])))
        self.deformable = self.rigid = None
        if self.fields.comm.rank == 0:
            from femcontact.outputs.xdmf import XdmfSeries

            try:
                self.deformable = XdmfSeries(Path(case_dir) / "fields.xdmf", self.fields.points, self.fields.cells,
                                             self.fields.cell_type)
                rigid = _rigid_mesh(p)
                if rigid is not None:
                    self.rigid_points = rigid[0]
                    self.rigid = XdmfSeries(Path(case_dir) / "rigid.xdmf", *rigid)
            except InputError as failure:
                self.error = failure

    def detach(self) -> None:
        self.fields.detach()

    def __call__(self, row: dict, cuts: int = 0) -> None:
        self.increments += 1
        end = abs(row["time"] - self.step_ends.get(row["step"], np.inf)) <= 1e-9 * max(1.0, abs(row["time"]))
        if self.increments % self.every and not end:
            return
        frame = self.fields.gather()
        if frame is None or self.error is not None:
            return
        point_data, cell_data = frame
        point_data.pop("contact_area")
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
