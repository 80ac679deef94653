"""The discrete problem of a scene: unknowns, the effects' terms and the compiled forms.

Like DOLFINx's `NonlinearProblem`, `Problem` owns the forms and exposes them (`forms`);
the solver only assembles them. The residual of the deformable body is

    R_u = sum(bulk terms) dx + sum(contact terms) ds_contact,   contact terms = -t . v + ...

with the contact traction t summed from what the effects add. Effects are built in the
order of `femcontact.effects.components_for`; `built` lists them, and only they exist:
a frictionless quasi-static scene has no history state at all.
"""
import functools
from types import SimpleNamespace

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from femcontact.config.scene import deformable_body
from femcontact.effects import components_for
from femcontact.effects.contact import EXACT_SURFACE_RULE, P2_NODE_RULE, VERTEX_RULE
from femcontact.errors import InputError
from femcontact.jit import compile_forms
from femcontact.physics.rigid_body import scene_rigid_body
from femcontact.physics.rotation import rotation_numpy

SHAPE_PARAMETERS = ("half_width", "length", "radius", "corner_radius", "depth", "block_width", "bottom_thickness")


class Forms(SimpleNamespace):
    """A problem's compiled forms; the whole Jacobian only when a solver first asks for it
    (whether it does depends on its options: solver/linear.py)."""

    @functools.cached_property
    def jacobian(self):
        return fem.form(self.jacobian_integrand)


class Problem:
    """Unknowns, effects and forms of one scene on one mesh."""

    def __init__(self, scene: dict, model):
        self.scene, self.model = scene, model
        self.mesh, self.dim = model.mesh, model.mesh.geometry.dim
        self.effects = tuple(scene["effects"])
        if not model.supports:
            raise InputError(f"rigid = {scene['rigid']!r}: the deformable body has no support; "
                             "make it the rigid body instead")
        self.deformable = deformable_body(scene)
        degree = scene["mesh"]["degree"]
        self.V = fem.VectorFunctionSpace(self.mesh, ("Lagrange", degree))
        self.u = fem.Function(self.V, name="displacement")
        self.v = ufl.TestFunction(self.V)
        self.dx = ufl.Measure("dx", domain=self.mesh)
        self.ds_contact = self.contact_measure()
        self.shape = self._shape_constants(model.rigid)
        self.rigid = scene_rigid_body(scene, self.mesh, model.rigid)
        self.bcs = self._supports()

        self._bulk, self._contact_terms, self._traction = [], [], []
        self.time_stepping = None  # the effect that steps the rigid body's motion in time, if any (it sets itself)
        self.components = components_for(self)
        values = {}
        for component in self.components:
            values.update(component.constants(scene, self.deformable))
        self.constants = {name: fem.Constant(self.mesh, float(value)) for name, value in values.items()}
        for component in self.components:
            component.build(self)
        self.built = [component.name for component in self.components]
        self.bulk = sum(self._bulk)
        self.traction = sum(self._traction)
        self.contact_integrand = sum([-ufl.dot(self.traction, self.v)] + self._contact_terms)
        self.forms = self._compile()

    # -- what effects call while they build ----------------------------------------------
    def add_bulk(self, integrand, dx=None) -> None:
        """A term of R_u integrated over the deformable body (N/mm^3 . test function), by
        `dx` if the term needs its own quadrature rule (a state kept at quadrature points)."""
        self._bulk.append(integrand * (dx or self.dx))

    def add_traction(self, traction) -> None:
        """A traction (MPa) the rigid body exerts on the contact surface."""
        self._traction.append(traction)

    def add_contact_term(self, integrand) -> None:
        """A term of R_u integrated over the contact surface, beside -t . v."""
        self._contact_terms.append(integrand)

    # -- forms ---------------------------------------------------------------------------
    def _compile(self) -> Forms:
        """The forms the solver assembles, compiled together (`compile_forms`) but for the whole
        `jacobian`, compiled when first used. `jacobian_bulk` is the bulk stiffness where it does
        not depend on the state, only on `bulk_constants` (the solver may then factor it once:
        solver/linear.py), else None. `contact_dr` maps each free rigid dof to the contact
        vector's derivative by it; a held or prescribed dof is no unknown and has none."""
        du = ufl.TrialFunction(self.V)
        contact = self.contact_integrand * self.ds_contact
        d_contact_dr = ufl.diff(self.contact_integrand, self.rigid.variable)
        bulk_jacobian = ufl.algorithms.expand_derivatives(ufl.derivative(self.bulk, self.u, du))
        state_free = not bulk_jacobian.coefficients()
        self.bulk_constants = bulk_jacobian.constants() if state_free else ()
        free = [int(j) for j in np.flatnonzero(self.rigid.free)]
        bulk_stiffness = [bulk_jacobian] if state_free else []
        residual_bulk, residual_contact, jacobian_contact, *compiled = compile_forms(
            [self.bulk, contact, ufl.derivative(contact, self.u, du), *bulk_stiffness]
            + [d_contact_dr[j] * self.ds_contact for j in free])
        jacobian_bulk = compiled.pop(0) if state_free else None
        return Forms(residual_bulk=residual_bulk, residual_contact=residual_contact, jacobian_contact=jacobian_contact,
                     jacobian_bulk=jacobian_bulk, contact_dr=dict(zip(free, compiled)),
                     jacobian_integrand=ufl.derivative(self.bulk + contact, self.u, du))

    def contact_measure(self, nodes: bool = False):
        """Contact terms use a fixed rule, so the residual and its derivatives integrate alike,
        with points on the element nodes (node-to-surface contact: a penetrating corner or edge
        node is seen at once). In 2-D it is Gauss-Lobatto; basix has no such rule on triangles,
        so in 3-D the rules are custom: P1 the facet's vertices (`VERTEX_RULE`; the nodes also lie
        on the exact curved surface, the facets' interior does not), P2 its nodes and centroid
        (`P2_NODE_RULE`, on exact surfaces too). On P1's exact surfaces (`contact.surface =
        "exact"`) the points are the vertices and edge midpoints, each facet's vertex rule on its
        four halved triangles (`EXACT_SURFACE_RULE`). `nodes`: the points are the displacement's
        nodes only (P2: without the centroid), for values lumped node by node."""
        degree = self.scene["mesh"]["degree"]
        if nodes and self.dim == 3:
            rule = VERTEX_RULE if degree == 1 else EXACT_SURFACE_RULE
            quadrature = {"quadrature_rule": "custom", "quadrature_degree": degree, **rule}
        elif self.dim == 2:
            quadrature = {"quadrature_rule": "GLL", "quadrature_degree": 2 * degree - 1}
        elif degree == 1 and self.scene["contact"]["surface"] == "exact":
            quadrature = {"quadrature_rule": "custom", "quadrature_degree": 1, **EXACT_SURFACE_RULE}
        elif degree == 1:
            quadrature = {"quadrature_rule": "custom", "quadrature_degree": 1, **VERTEX_RULE}
        else:
            quadrature = {"quadrature_rule": "custom", "quadrature_degree": 3, **P2_NODE_RULE}
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.model.facet_tags, metadata=quadrature)
        return ds(tuple(self.model.facets[name] for name in self.model.contact_facets))

    def _shape_constants(self, rigid: dict) -> dict:
        """The rigid shape with its sizes as Constants, so sweeps reuse compiled forms (a peg's tip
        chamfer stays a number: its form is compiled per chamfer)."""
        shape = dict(rigid)
        for key in SHAPE_PARAMETERS:
            if key in shape:
                shape[key] = fem.Constant(self.mesh, float(shape[key]))
        shape["scale"] = max(float(rigid.get(k, 0.0)) for k in SHAPE_PARAMETERS)
        return shape

    def _supports(self) -> list:
        """Clamped supports (support_dofs: name -> nodes) and symmetry planes, each holding one
        displacement component (symmetry_dofs: name -> unrolled dofs)."""
        self.support_dofs, self.symmetry_dofs = {}, {}
        bcs = []
        for name in self.model.supports:
            facets = self.model.facet_tags.find(self.model.facets[name])
            dofs = fem.locate_dofs_topological(self.V, self.dim - 1, facets)
            self.support_dofs[name] = dofs
            bcs.append(fem.dirichletbc(np.zeros(self.dim, dtype=np.float64), dofs, self.V))
        for name, component in self.model.symmetry.items():
            facets = self.model.facet_tags.find(self.model.facets[name])
            dofs = fem.locate_dofs_topological(self.V.sub(component), self.dim - 1, facets)
            self.symmetry_dofs[name] = dofs
            bcs.append(fem.dirichletbc(0.0, dofs, self.V.sub(component)))
        return bcs

    @property
    def support_dof_set(self) -> set:
        """Local (unrolled) indices of all held dofs: supports and symmetry planes."""
        held = {int(self.dim * node + k) for dofs in self.support_dofs.values() for node in dofs for k in range(self.dim)}
        return held.union(int(dof) for dofs in self.symmetry_dofs.values() for dof in dofs)

    @property
    def dofs(self) -> int:
        """The displacement unknowns over all ranks."""
        return self.V.dofmap.index_map.size_global * self.V.dofmap.index_map_bs

    @property
    def body_size(self) -> float:
        """The rigid body's largest dimension (mm): the arm that turns its rotations into lengths."""
        return self.shape["scale"]

    @property
    def rigid_arms(self) -> np.ndarray:
        """Per rigid dof, the length (mm) that turns it into a displacement and its residual row
        into a force: 1 for a translation, `body_size` for a rotation."""
        return np.where(np.arange(len(self.rigid.names)) < self.dim, 1.0, self.body_size)

    def rigid_length(self, change) -> float:
        """The largest displacement (mm) a change of the rigid dofs (mm, rad) makes: a rotation
        by its arm (`rigid_arms`)."""
        return float(np.abs(np.asarray(change) * self.rigid_arms).max())

    @property
    def contact_size(self) -> float:
        """The element size in the contact zones (mm)."""
        return self.model.h_contact

    def stiffness_scale(self) -> float:
        """The modulus that sets the scale of the deformable body's stiffness (MPa), from the effects."""
        return max([c.stiffness_scale() for c in self.components] + [0.0])

    def contact_stiffness(self) -> float:
        """The stiffness of the contact against a gap (N/mm^3: traction per mm of penetration),
        from the effects."""
        return max([c.contact_stiffness() for c in self.components] + [0.0])

    @functools.cached_property
    def extent(self) -> float:
        """The largest |coordinate| of any dof node, over all ranks (mm): the scale of the
        round-off in positions."""
        local = float(np.abs(self.V.tabulate_dof_coordinates()).max(initial=0.0))
        return self.mesh.comm.allreduce(local, op=MPI.MAX)

    def local_coordinates(self) -> np.ndarray:
        """Current position of every dof node in the rigid body's shape frame (numpy, mm)."""
        x = self.V.tabulate_dof_coordinates()[:, : self.dim] + self.u.x.array.reshape(-1, self.dim)
        t, angles = self.rigid.split(self.rigid.values)
        R = rotation_numpy(angles) @ self.rigid.Q0
        return (x - self.rigid.p0 - np.asarray(t)) @ R

    # -- what the solver calls -----------------------------------------------------------
    def rigid_residual(self, load) -> np.ndarray:
        """The effects' terms of the rigid body's residual (N, N*mm)."""
        terms = [c.rigid_residual(load) for c in self.components]
        return sum((t for t in terms if t is not None), np.zeros(len(self.rigid.names)))

    def rigid_stiffness(self, load) -> np.ndarray:
        terms = [c.rigid_stiffness(load) for c in self.components]
        return sum((t for t in terms if t is not None), np.zeros((len(self.rigid.names),) * 2))

    def add_contact_residual(self, vector) -> None:
        for component in self.components:
            component.add_contact_residual(vector)

    def add_contact_jacobian(self, matrices, kur, bc_dofs: set) -> None:
        for component in self.components:
            component.add_contact_jacobian(matrices, kur, bc_dofs)

    def load_scale(self) -> float:
        """Largest load the effects apply themselves (N), e.g. the rigid body's weight."""
        return max([c.load_scale() for c in self.components] + [0.0])

    def begin_increment(self, load) -> None:
        for component in self.components:
            component.begin_increment(load)

    def lock_contacts(self, on: bool) -> bool:
        """Every contact point sticks (on) or follows the scene's friction law again (off);
        False if no effect has a friction law to change."""
        return any([component.lock_contacts(on) for component in self.components])

    def path_dependent(self) -> bool:
        """Whether several equilibria may hold one load, so that an increment's answer depends on
        the solver's path to it (`Effect.path_dependent`: friction)."""
        return any(component.path_dependent() for component in self.components)

    def commit(self, dt: float) -> None:
        """Accept the converged increment: each effect updates its history, then the pose."""
        for component in self.components:
            component.commit(dt)
        self.rigid.commit()

    def commit_contacts(self) -> None:
        """Move the contact's history (friction anchors, slip) to the current state, the material's
        and the rigid body's motion left at the increment's start (`Effect.commit_contacts`)."""
        for component in self.components:
            component.commit_contacts()

    def state(self) -> dict:
        """Copy of everything an increment changes (to retry a cut increment, checkpoints)."""
        state = {"u": self.u.x.array.copy(), "r": self.rigid.values.copy(), "r_old": self.rigid.r_old.value.copy()}
        for component in self.components:
            state.update({f"{component.name}.{key}": value for key, value in component.state().items()})
        return state

    def restore(self, state: dict) -> None:
        self.u.x.array[:] = state["u"]
        self.rigid.values[:] = state["r"]
        self.rigid.r_old.value[:] = state["r_old"]
        self.rigid.sync()
        for component in self.components:
            prefix = f"{component.name}."
            own = {key[len(prefix):]: value for key, value in state.items() if key.startswith(prefix)}
            if own:
                component.restore(own)
