"""Coulomb friction by a return map on a stick anchor (history).

Each contact point remembers its anchor: the point of the rigid body, in the rigid body's
frame, that it sticks to. The trial traction is -gamma_T times the tangential distance
from the anchor (gamma_T = gamma_t E / h_contact, N/mm^3); it is projected on the disc of
radius mu p (`physics.coulomb`). After each converged increment the anchor moves so that the
next increment starts from the converged traction, so a load that is removed leaves the
stuck state in place (and a peg that turns and slides is handled: anchors live in its frame).

The anchors are a discontinuous field, one value per element node: the pressure p and so
the bound mu p differ between the two facets that meet at a node (the Nitsche pressure
uses each element's own stress), and a facet's anchor must hold that facet's traction for
the next increment to start exactly where the last one converged. With the contact rules
that integrate at the nodes (2-D, and 3-D P1) this holds to round-off, also at a node shared
by two contact facets of one element (a hole's mouth edge: `commit` keeps the larger of their
tractions, which both facets clip back to their own); 3-D P2 adds each facet's centroid,
whose anchor is interpolated from the element's nodes. The field
lives on every element (DOLFINx 0.5 has no function space on facets): d numbers per node of
each element, in 3-D P1 about 24 per mesh vertex. On exact surfaces (`contact.surface`) the
contact points include the edge midpoints: the anchors are quadratic there, one per node.
"""
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

from femcontact.effects.base import Effect
from femcontact.effects.contact import summed_vector
from femcontact.jit import compile_forms
from femcontact.physics.coulomb import coulomb_projection, sticks
from femcontact.physics.rotation import rotation_numpy


STUCK_MU = 1e6  # a friction coefficient under which every touching point sticks (`lock_contacts`)


def contact_layers(problem) -> list:
    """The contact measure split into layers (ds measures with its quadrature rule) such that no
    element has two facets in one layer: an element's contact facets in the order of their
    midpoints (x, then y, then z), the first in layer 1, the second in layer 2, ... The order
    is the geometry's, so every rank assigns a facet alike."""
    from dolfinx.mesh import compute_midpoints, meshtags

    mesh, model = problem.mesh, problem.model
    tdim = mesh.topology.dim
    contact_tags = [model.facets[name] for name in model.contact_facets]
    facets = np.sort(model.facet_tags.indices[np.isin(model.facet_tags.values, contact_tags)])
    mesh.topology.create_connectivity(tdim - 1, tdim)
    facet_cells = mesh.topology.connectivity(tdim - 1, tdim)
    midpoints = compute_midpoints(mesh, tdim - 1, facets)
    by_cell = {}
    for facet, midpoint in zip(facets, midpoints):
        by_cell.setdefault(int(facet_cells.links(facet)[0]), []).append((tuple(midpoint), int(facet)))
    layer = np.zeros(len(facets), dtype=np.int32)
    position = {facet: k for k, facet in enumerate(facets)}
    for entries in by_cell.values():
        for k, (_, facet) in enumerate(sorted(entries)):
            layer[position[facet]] = k + 1
    count = mesh.comm.allreduce(int(layer.max(initial=1)), op=MPI.MAX)
    tags = meshtags(mesh, tdim - 1, facets.astype(np.int32), layer)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=problem.ds_contact.metadata())
    return [ds(k) for k in range(1, count + 1)]


class Friction(Effect):
    name = "friction"

    def constants(self, scene: dict, body: str) -> dict:
        contact = scene["contact"]
        return {"mu": contact["mu"], "gamma_t": contact["gamma_t"] or contact["gamma"]}

    def path_dependent(self) -> bool:
        """Whether friction acts (mu > 0): then several stick-slip states may hold one load."""
        return float(self.problem.constants["mu"].value) > 0

    def build(self, problem) -> None:
        c, rigid, contact = problem.constants, problem.rigid, problem.contact
        degree = problem.scene["mesh"]["degree"]
        exact = problem.scene["contact"]["surface"] == "exact"  # contact points on edge midpoints too (P1)
        self.W = fem.VectorFunctionSpace(problem.mesh, ("DG", max(degree, 2) if exact else degree))
        self.anchor = fem.Function(self.W, name="anchor")
        if exact:  # the points where the contact is measured, moved onto the exact surface
            self._position = fem.Expression(contact.xi, self.W.element.interpolation_points())
        else:  # the nodes' local coordinates, to interpolate on W
            self._position = fem.Function(problem.V)
        self.anchor.interpolate(self._local_coordinates())  # every node starts stuck
        slip_local = contact.xi - self.anchor
        slip_local = slip_local - ufl.dot(slip_local, contact.normal_local) * contact.normal_local
        trial = -c["gamma_t"] * c["E"] / problem.model.h_contact * rigid.to_global_direction(slip_local, rigid.variable)
        normal, bound = contact.normal, c["mu"] * contact.pressure
        if problem.dim == 2:  # the trial's component along the tangent
            tangent = ufl.as_vector([-normal[1], normal[0]])
            trial = ufl.dot(trial, tangent)
            tangential = coulomb_projection(trial, bound) * tangent
        else:
            tangential = coulomb_projection(trial, bound)
        touching, stuck = ufl.gt(contact.pressure, 0), sticks(trial, bound)
        self.stick = ufl.conditional(ufl.And(touching, stuck), 1.0, 0.0)
        self.slip = ufl.conditional(ufl.And(touching, ufl.Not(stuck)), 1.0, 0.0)
        problem.add_traction(tangential)
        v, w = ufl.TestFunction(self.W), ufl.TrialFunction(self.W)
        # the L2 projection onto the contact trace is for elements whose lumped areas vanish (P2
        # facets in 3-D: a quadratic triangle's vertex functions integrate to zero); its tiny volume
        # term (relative 1e-10 per element size) only makes the matrix regular off the contact facets
        size = problem.model.h_contact
        layers = contact_layers(problem)
        self.layer_forms = compile_forms([form for ds in layers for form in (
            ufl.dot(tangential, v) * ds, sum(v[k] for k in range(problem.dim)) * ds)])
        self.projection_form, = compile_forms([
            ufl.inner(w, v) * problem.ds_contact + 1e-10 * size * ufl.inner(w, v) * problem.dx])
        self.projection = None

    def lock_contacts(self, on: bool) -> bool:
        """mu = STUCK_MU (on) or the scene's mu (off)."""
        self.problem.constants["mu"].value = STUCK_MU if on else self.problem.scene["contact"]["mu"]
        return True

    def commit(self, dt: float) -> None:
        """Move each anchor so that -gamma_T (xi - anchor) equals the converged tangential
        traction t: anchor = xi + R^T t / gamma_T. t at an element node is its share of the
        integral of t over a contact facet divided by its share of the facet's area; where an
        element has several contact facets at the node (`contact_layers`), the largest of
        their tractions: they share the trial traction and differ only where a facet's bound
        mu p clips it, so the largest is the one trial that each facet clips to its own
        traction again. Where some node's share of area vanishes (P2 in 3-D: a quadratic
        triangle's vertex functions integrate to zero), the L2 projection of t on the anchors'
        space instead."""
        p = self.problem
        vectors = [summed_vector(form) for form in self.layer_forms]
        arrays = []
        for vector in vectors:
            with vector.localForm() as local:
                arrays.append(local.array.reshape(-1, p.dim).copy())
        forces, weights = arrays[0::2], [a[:, :1] for a in arrays[1::2]]
        if self.projection is None:  # decided once: the areas depend only on the mesh
            weight = sum(weights)
            largest = p.mesh.comm.allreduce(float(np.abs(weight).max(initial=0.0)), op=MPI.MAX)
            degenerate = np.any((weight != 0) & (np.abs(weight) < 1e-9 * largest))
            self.projection = bool(p.mesh.comm.allreduce(degenerate, op=MPI.LOR))
        if self.projection:
            force_vector = vectors[0].copy()
            for vector in vectors[2::2]:
                force_vector.axpy(1.0, vector)
            traction = self._projected_traction(force_vector)
            force_vector.destroy()
        else:
            tractions = np.array([np.where(w > 0, f / np.where(w > 0, w, 1.0), 0.0) for f, w in zip(forces, weights)])
            largest = np.argmax(np.linalg.norm(tractions, axis=2), axis=0)
            traction = tractions[largest, np.arange(tractions.shape[1])]
        for vector in vectors:
            vector.destroy()
        R = rotation_numpy(p.rigid.split(p.rigid.values)[1]) @ p.rigid.Q0
        gamma_t = float(p.constants["gamma_t"].value * p.constants["E"].value) / p.model.h_contact
        self.anchor.interpolate(self._local_coordinates())
        self.anchor.x.array[:] += (traction @ R / gamma_t).reshape(-1)

    def commit_contacts(self) -> None:
        """The anchors moved to the current state (`commit`: they hold no time)."""
        self.commit(0.0)

    def _local_coordinates(self):
        """The contact points in the rigid body's frame (mm): the deformable body's nodes as a
        function on V, or on exact surfaces the expression of the contact's xi."""
        if isinstance(self._position, fem.Function):
            self._position.x.array[:] = self.problem.local_coordinates().reshape(-1)
        return self._position

    def _projected_traction(self, force_vector) -> np.ndarray:
        """Traction t (MPa) at the anchors' nodes, local and ghost, with M t = F: M the contact
        trace's mass matrix, F the integral of the converged traction."""
        p = self.problem
        matrix = petsc.assemble_matrix(self.projection_form)
        matrix.assemble()
        ksp = PETSc.KSP().create(p.mesh.comm)
        ksp.setOperators(matrix)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        solution = force_vector.duplicate()
        ksp.solve(force_vector, solution)
        solution.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with solution.localForm() as local:
            traction = local.array.reshape(-1, p.dim).copy()
        for item in (ksp, matrix, solution):
            item.destroy()
        return traction

    def state(self) -> dict:
        return {"anchor": self.anchor.x.array.copy()}

    def restore(self, state: dict) -> None:
        self.anchor.x.array[:] = state["anchor"]

    def nodal_outputs(self) -> dict:
        return {"stick": self.stick, "slip": self.slip}
