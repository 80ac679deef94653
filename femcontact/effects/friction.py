"""Coulomb friction by a return map on a stick anchor (history).

Each contact node remembers its anchor: the point of the rigid body, in the rigid body's
frame, that it sticks to. The trial traction is -gamma_T times the tangential distance
from the anchor (gamma_T = gamma_t E / h_contact, N/mm^3); it is projected on the disc of
radius mu p (`physics.coulomb`). After each converged increment the anchor moves so that the next increment
starts from the converged traction, so a load that is removed leaves the stuck state in
place (and a peg that turns and slides is handled: anchors live in its frame).
"""
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

from femcontact.effects.base import Effect
from femcontact.physics.coulomb import coulomb_projection, sticks
from femcontact.physics.rotation import rotation_numpy


class Friction(Effect):
    name = "friction"

    def constants(self, scene: dict, body: str) -> dict:
        contact = scene["contact"]
        return {"mu": contact["mu"], "gamma_t": contact["gamma_t"] or contact["gamma"]}

    def build(self, problem) -> None:
        c, rigid, contact = problem.constants, problem.rigid, problem.contact
        self.anchor = fem.Function(problem.V, name="anchor")
        self.anchor.x.array[:] = problem.local_coordinates().reshape(-1)  # every node starts stuck
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
        v, w = ufl.TestFunction(problem.V), ufl.TrialFunction(problem.V)
        self.area_form = fem.form(sum(v[k] for k in range(problem.dim)) * problem.ds_contact)
        # L2 projection onto the contact trace, for elements whose lumped areas vanish (P2 facets
        # in 3-D: a quadratic triangle's vertex functions integrate to zero); the tiny volume term
        # (relative 1e-10 per element size) only makes the matrix regular off the contact facets
        size = problem.model.h_contact
        self.projection_form = fem.form(ufl.inner(w, v) * problem.ds_contact + 1e-10 * size * ufl.inner(w, v) * problem.dx)
        self.projection = None

    def commit(self, dt: float) -> None:
        """Move each node's anchor so that -gamma_T (xi - anchor) equals the converged
        tangential traction: anchor = xi + R^T t / gamma_T. The traction per node is its
        contact force (integral terms only) over its lumped contact area; where some contact
        node's lumped area vanishes (P2 in 3-D), the L2 projection of the contact force on the
        contact trace instead (`_projected_traction`)."""
        p = self.problem
        vectors, force_vector = [], None
        for form in (p.forms.residual_contact, self.area_form):
            vector = petsc.assemble_vector(form)
            vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            with vector.localForm() as local:
                vectors.append(local.array.reshape(-1, p.dim).copy())
            if force_vector is None:
                force_vector = vector
            else:
                vector.destroy()
        force, weight = vectors[0], vectors[1][:, :1]
        if self.projection is None:  # decided once: the lumped areas depend only on the mesh
            largest = p.mesh.comm.allreduce(float(np.abs(weight).max(initial=0.0)), op=MPI.MAX)
            degenerate = np.any((weight != 0) & (np.abs(weight) < 1e-9 * largest))
            self.projection = bool(p.mesh.comm.allreduce(degenerate, op=MPI.LOR))
        if self.projection:
            traction = self._projected_traction(force_vector)
        else:
            traction = np.where(weight > 0, -force / np.where(weight > 0, weight, 1.0), 0.0)
        force_vector.destroy()
        R = rotation_numpy(p.rigid.split(p.rigid.values)[1]) @ p.rigid.Q0
        gamma_t = float(p.constants["gamma_t"].value * p.constants["E"].value) / p.model.h_contact
        self.anchor.x.array[:] = (p.local_coordinates() + traction @ R / gamma_t).reshape(-1)

    def _projected_traction(self, force_vector) -> np.ndarray:
        """Nodal traction t (MPa, local and ghost nodes) with M t = -f, M the contact trace's mass matrix."""
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
            traction = -local.array.reshape(-1, p.dim).copy()
        for item in (ksp, matrix, solution):
            item.destroy()
        return traction

    def state(self) -> dict:
        return {"anchor": self.anchor.x.array.copy()}

    def restore(self, state: dict) -> None:
        self.anchor.x.array[:] = state["anchor"]

    def nodal_outputs(self) -> dict:
        return {"stick": self.stick, "slip": self.slip}
