"""What a simulation reports after each increment, correct under MPI.

Reactions come from the assembled residual at the support dofs (variationally
consistent, so they balance the rigid body's load to solver tolerance); contact
resultants from the contact residual, per zone (A: x < 0, B: x > 0 for a peg in a
hole or the springs of a snap fit, one zone `top` for a block); nodal contact pressure and stick/slip states
from boundary integrals at the displacement's nodes, lumped node by node.
"""
import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from femcontact.errors import InputError
from femcontact.jit import compile_forms


class Recorder:
    """Computes one row of outputs per increment from a solved Problem."""

    def __init__(self, problem, newton):
        self.problem, self.newton = problem, newton
        self.observers = []  # called after each row, while the increment's state is not yet committed
        p, comm = problem, problem.mesh.comm
        self.comm = comm
        degree = p.scene["mesh"]["degree"]
        self.W = fem.FunctionSpace(p.mesh, ("DG", degree - 1))
        self.von_mises = fem.Function(self.W, name="von_mises")
        self.von_mises_expression = fem.Expression(p.von_mises, self.W.element.interpolation_points())
        pressure = p.contact.pressure
        # the effects' contact states (friction: stick, slip) weighted by the pressure: a node is in
        # the state that carries most of its contact force
        states = {name: pressure * value for component in p.components
                  for name, value in component.nodal_outputs().items()}
        self.states = list(states)  # counted per row as <name>_nodes, beside active_nodes
        self.nodal_names = ["pressure", *states, "area"]
        values = [pressure, *states.values(), 1.0]
        self.Q = fem.VectorFunctionSpace(p.mesh, ("Lagrange", degree), dim=len(values))
        q = ufl.TestFunction(self.Q)
        self.energy, self.nodal_form = compile_forms([p.energy_density * p.dx, sum(
            value * q[i] for i, value in enumerate(values)) * p.contact_measure(nodes=True)])
        self.nodal = fem.Function(self.Q)
        n_owned = p.V.dofmap.index_map.size_local
        x = newton.coordinates
        self.contact_facets = np.unique(np.concatenate([np.zeros(0, dtype=np.int32)] + [
            p.model.facet_tags.find(p.model.facets[name]) for name in p.model.contact_facets]))
        nodes = fem.locate_dofs_topological(p.V, p.dim - 1, self.contact_facets)
        self.contact_nodes = nodes[nodes < n_owned]  # this rank's owned nodes of the contact surface
        on_contact = np.zeros(n_owned, dtype=bool)
        on_contact[self.contact_nodes] = True
        if p.scene["geometry"] in ("peg_in_hole", "snap_fit"):
            self.zones = {"A": on_contact & (x[:, 0] < 0), "B": on_contact & (x[:, 0] >= 0)}
        else:
            self.zones = {"top": on_contact}
        self.columns = self._columns()
        check_stop_columns(p.scene, self.columns)
        self._recovery = None  # `recovered_pressure`'s expression, compiled on first use

    def _columns(self) -> list[str]:
        """The names of a row's values, in order (history.csv's header)."""
        p, dim = self.problem, self.problem.dim
        axes, moments = "xyz"[:dim], (["z"] if dim == 2 else list("xyz"))
        columns = ["step", "time", "dt", "newton_iterations", *(f"rigid_{name}" for name in p.rigid.names),
                   "tilt_deg", *(f"applied_F{axis}" for axis in axes)]
        for name in p.support_dofs:
            columns += [*(f"reaction_{name}_{axis}" for axis in axes), f"reaction_{name}",
                        *(f"reaction_{name}_M{axis}" for axis in moments)]
        for zone in self.zones:
            columns += [*(name for axis in axes for name in (f"contact_{zone}_F{axis}", f"contact_{zone}_{axis}")),
                        f"contact_{zone}_force"]
        columns += ["max_pressure", "active_nodes", *(f"{state}_nodes" for state in self.states)]
        for component in p.components:
            columns += list(component.outputs())
        return columns + ["elastic_energy", "max_von_mises", "yielded", "stabilization_force"]

    def _sum(self, value):
        return self.comm.allreduce(value, op=MPI.SUM)

    def _max(self, value):
        return self.comm.allreduce(value, op=MPI.MAX)

    def nodal_values(self) -> dict:
        """Contact values on this rank's owned nodes of the displacement (pressure in MPa), each the
        mean over the node's contact facets at the node; the states weighted by the pressure."""
        assemble_nodal(self.nodal, self.nodal_form)
        n, k = self.Q.dofmap.index_map.size_local, len(self.nodal_names)
        values = self.nodal.x.array[: n * k].reshape(-1, k)
        area = values[:, -1]
        where = area > 0
        out = {name: np.where(where, values[:, i] / np.where(where, area, 1), 0.0)
               for i, name in enumerate(self.nodal_names[:-1])}
        out["coordinates"] = self.Q.tabulate_dof_coordinates()[:n]
        out["on_surface"] = where
        return out

    def recovered_pressure(self) -> tuple[np.ndarray, np.ndarray]:
        """The contact pressure (MPa) at the displacement's nodes of the contact surface (this
        rank's owned ones; coordinates in mm): the argument of the pressure's [.]_+ evaluated in
        every cell with one contact facet (its stress on that facet's normal), averaged over those
        cells at each node, then [.]_+: the contact zone's edge lies where the argument changes
        sign (`nodal_values` averages each facet's [.]_+ instead). A node whose cells each have
        several contact facets (a corner) has no value and is left out."""
        if self._recovery is None:
            self._recovery = _PressureRecovery(self.problem, self.contact_facets, self.contact_nodes)
        return self._recovery()

    def row(self, load, iterations: int, stabilization_force: float = 0.0) -> dict:
        """The outputs after a converged increment; `stabilization_force` (N): the contact
        stabilisation's force kept in it (0 for an exact solve)."""
        p, newton = self.problem, self.newton
        dim, rigid = p.dim, p.rigid
        row = {"step": p.scene["steps"][load.step]["name"], "time": load.time, "dt": load.dt,
               "newton_iterations": iterations}
        for name, value in zip(rigid.names, rigid.values):
            row[f"rigid_{name}"] = float(value)
        row["tilt_deg"] = np.degrees(rigid.tilt())
        for k, axis in enumerate("xyz"[:dim]):
            row[f"applied_F{axis}"] = float(load.force[k])

        R_u, _, _ = newton.current_residual(load)  # and newton.b_bulk, b_contact there
        full = newton.b_bulk.array_r + newton.b_contact.array_r
        full = full.reshape(-1, dim)
        x = newton.coordinates + p.u.x.array[: newton.n_owned * dim].reshape(-1, dim)
        for name, dofs in p.support_dofs.items():
            owned = dofs[dofs < newton.n_owned]
            force = np.array([self._sum(full[owned, k].sum()) for k in range(dim)])
            for k, axis in enumerate("xyz"[:dim]):
                row[f"reaction_{name}_{axis}"] = force[k]
            row[f"reaction_{name}"] = float(np.linalg.norm(force))
            moment = np.atleast_1d(np.cross(x[owned], full[owned]).sum(axis=0))  # about the origin
            for k, axis in enumerate(["z"] if dim == 2 else "xyz"):
                row[f"reaction_{name}_M{axis}"] = self._sum(float(moment[k]))

        contact = newton.b_contact.array_r.reshape(-1, dim)
        for zone, mask in self.zones.items():
            f = -contact[mask]  # force of the rigid body on the deformable one
            force = np.array([self._sum(f[:, k].sum()) for k in range(dim)])
            weight = np.linalg.norm(f, axis=1)
            total = self._sum(weight.sum())
            centre = np.array([self._sum((x[mask, k] * weight).sum()) for k in range(dim)]) / (total or 1.0)
            for k, axis in enumerate("xyz"[:dim]):
                row[f"contact_{zone}_F{axis}"] = force[k]
                row[f"contact_{zone}_{axis}"] = centre[k] if total > 0 else None  # no contact: no centre
            row[f"contact_{zone}_force"] = float(np.linalg.norm(force))

        nodal = self.nodal_values()
        row["max_pressure"] = self._max(float(nodal["pressure"].max(initial=0.0)))
        active = nodal["pressure"] > 0
        row["active_nodes"] = int(self._sum(int(active.sum())))
        if self.states:
            weights = np.column_stack([nodal[state] for state in self.states])
            held = np.argmax(weights, axis=1)
            for i, state in enumerate(self.states):
                row[f"{state}_nodes"] = int(self._sum(int((active & (held == i)).sum())))
        for component in p.components:
            row.update(component.outputs())
        row["elastic_energy"] = self._sum(fem.assemble_scalar(self.energy))
        self.von_mises.interpolate(self.von_mises_expression)
        n = self.W.dofmap.index_map.size_local
        row["max_von_mises"] = self._max(float(self.von_mises.x.array[:n].max(initial=0.0)))
        row["yielded"] = bool(row["max_von_mises"] > p.scene["materials"][p.deformable]["yield_stress"])
        row["stabilization_force"] = stabilization_force
        for observe in self.observers:
            observe()
        return row


class _PressureRecovery:
    """`Recorder.recovered_pressure`'s cells, normals and expression, made on first use. The
    pressure's argument is evaluated at the displacement's nodes of every cell with one contact
    facet, the facet normal n (which enters Nitsche's stress term and, with `contact.normal =
    "wall"`, the contact's direction) replaced by that facet's normal, held cell by cell in DG0
    fields."""

    def __init__(self, p, facets: np.ndarray, nodes: np.ndarray):
        """`facets`: this rank's contact facets; `nodes`: its owned nodes on them (V's blocks)."""
        from dolfinx import la
        from dolfinx.cpp.mesh import entities_to_geometry
        from dolfinx.mesh import compute_midpoints

        mesh, tdim = p.mesh, p.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        facet_cells = mesh.topology.connectivity(tdim - 1, tdim)
        cells = np.array([facet_cells.links(f)[0] for f in facets], dtype=np.int32)
        vertices = mesh.geometry.x[entities_to_geometry(mesh._mesh, tdim - 1, facets, False)][:, :, :tdim]
        if tdim == 2:
            edge = vertices[:, 1] - vertices[:, 0]
            normals = np.column_stack([edge[:, 1], -edge[:, 0]])
        else:
            normals = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
        outward = compute_midpoints(mesh, tdim - 1, facets)[:, :tdim] - compute_midpoints(mesh, tdim, cells)[:, :tdim]
        normals *= np.sign(np.sum(normals * outward, axis=1))[:, None] / np.linalg.norm(normals, axis=1)[:, None]
        unique, per_cell = np.unique(cells, return_counts=True)
        single = np.isin(cells, unique[per_cell == 1]) & (cells < mesh.topology.index_map(tdim).size_local)
        self.cells, self.normals = cells[single], normals[single]

        _, argument, _ = p.contact.pressure.ufl_operands  # conditional(argument >= 0, argument, 0)
        space = fem.FunctionSpace(mesh, ("DG", 0))  # scalar: the element Nitsche's cell size compiled
        dofs = space.dofmap.list.array.reshape(-1)[self.cells]
        components = [fem.Function(space) for _ in range(tdim)]
        for k, component in enumerate(components):
            component.x.array[dofs] = self.normals[:, k]
        V = p.V
        self.expression = fem.Expression(ufl.replace(argument, {ufl.FacetNormal(mesh): ufl.as_vector(components)}),
                                         V.element.interpolation_points())
        self.nodes_of_cells = V.dofmap.list.array.reshape(len(V.dofmap.list), -1)[self.cells]
        self.sum, self.count = la.vector(V.dofmap.index_map), la.vector(V.dofmap.index_map)
        self.add = la.ScatterMode.add
        self.nodes = nodes
        self.coordinates = V.tabulate_dof_coordinates()[nodes, :tdim]

    def __call__(self) -> tuple[np.ndarray, np.ndarray]:
        argument = np.zeros(self.nodes_of_cells.shape)
        if len(argument):  # a rank may own no cell on the contact surface
            argument[:] = self.expression.eval(self.cells).reshape(argument.shape)
        for vector, values in ((self.sum, argument.ravel()), (self.count, 1.0)):
            vector.array[:] = 0.0
            np.add.at(vector.array, self.nodes_of_cells.ravel(), values)
            vector.scatter_reverse(self.add)
        count = self.count.array[self.nodes]
        pressure = np.maximum(self.sum.array[self.nodes] / np.where(count > 0, count, 1.0), 0.0)
        return self.coordinates[count > 0], pressure[count > 0]


def assemble_nodal(function, form, add=None) -> None:
    """Assemble the vector `form` into `function`, each node's sum over every rank (its ghosts too);
    `add(array)`: adds this rank's entries that are not integrals to the local array first."""
    from dolfinx.fem import petsc
    from petsc4py import PETSc

    vec = function.vector
    with vec.localForm() as local:
        local.set(0.0)
    petsc.assemble_vector(vec, form)
    if add is not None:
        with vec.localForm() as local:
            add(local.array)
    vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)


def check_stop_columns(scene: dict, columns: list[str]) -> None:
    """Refuse a `steps[].stop.column` that names no history column (InputError listing them)."""
    for i, step in enumerate(scene["steps"]):
        column = step["stop"]["column"]
        if column and column not in columns:
            raise InputError(f"steps[{i}].stop.column = {column!r}: no such history column, expected one of "
                             + ", ".join(columns))
