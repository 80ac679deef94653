"""Monolithic Newton for the deformable body (u) and the rigid body (r) together.

Each iteration solves the bordered system

    [K_uu  K_ur] [du]     [R_u]
    [K_ru  K_rr] [dr] = - [R_r]

by eliminating the few rigid unknowns with a Schur complement: one factorisation of
K_uu serves the residual and the n_r columns of K_ur, then the small dense system
S dr = -R_r + K_ru y, S = K_rr - K_ru X, gives dr. The Jacobian is consistent: K_uu
and K_ur come from UFL derivatives of the residual, the rigid rows from the contact
vector C (N) tested with the rigid-body modes W(u, r) of the current configuration:

    R_r = -(Q_ext(r) + W^T C) + M a(r)      (forces N, moments N*mm)

A backtracking line search on |R|^2 damps the semismooth Newton where stick/slip
or contact sets change. A failed linear solve, a NaN or too many iterations raise
`NewtonFailure`, which the stepper answers by cutting the increment.
"""
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

DEFAULT_PETSC_OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


class NewtonFailure(RuntimeError):
    """Newton did not converge; `history` holds the residual norms per iteration."""

    def __init__(self, message: str, history: list):
        super().__init__(f"{message}; residual history {['%.3e' % r for r in history]}")
        self.history = history


class SchurNewton:
    """Newton solver with the rigid-body unknowns condensed by a Schur complement."""

    def __init__(self, problem, prefix: str = "femcontact_"):
        self.problem = problem
        p, comm = problem, problem.mesh.comm
        du = ufl.TrialFunction(p.V)
        contact = p.contact_integrand * p.ds_contact
        residual = sum(p.bulk) + contact
        self.residual_bulk = fem.form(sum(p.bulk))
        self.residual_contact = fem.form(contact)
        self.jacobian = fem.form(ufl.derivative(residual, p.u, du))
        self.jacobian_contact = fem.form(ufl.derivative(contact, p.u, du))
        n_r = len(p.rigid.names)
        d_contact_dr = ufl.diff(p.contact_integrand, p.rigid.variable)
        self.contact_dr = [fem.form(d_contact_dr[j] * p.ds_contact) for j in range(n_r)]

        self.K = petsc.create_matrix(self.jacobian)
        self.Kc = petsc.create_matrix(self.jacobian_contact)
        self.b_bulk = petsc.create_vector(self.residual_bulk)
        self.b_contact = petsc.create_vector(self.residual_contact)
        self.kur = [petsc.create_vector(form) for form in self.contact_dr]
        self.work = [p.u.vector.copy() for _ in range(2 * n_r + 3)]
        if "anchor" in p.history:
            v = ufl.TestFunction(p.V)
            self.area_form = fem.form(sum(v[k] for k in range(p.dim)) * p.ds_contact)
            self.area = petsc.create_vector(self.area_form)
            self.b_anchor = petsc.create_vector(self.residual_contact)

        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix(prefix)
        options = PETSc.Options()
        for key, value in {**DEFAULT_PETSC_OPTIONS, **p.scene["solver"]["petsc_options"]}.items():
            options[prefix + key] = value
        self.ksp.setFromOptions()
        self.ksp.setOperators(self.K)
        if options.getString(prefix + "pc_type", "") == "gamg":
            self.K.setNearNullSpace(self._rigid_body_modes())

        dim = p.dim
        n_owned = p.V.dofmap.index_map.size_local
        self.coordinates = p.V.tabulate_dof_coordinates()[:n_owned, :dim]
        self.n_owned = n_owned
        self.corner_contacts = 0
        self.bc_dofs = p.support_dof_set
        self.stabilization = np.zeros((n_r, n_r))  # viscous spring to the last converged pose (N/mm, N*mm)

    def _rigid_body_modes(self) -> PETSc.NullSpace:
        """Near-nullspace of elasticity (translations and rotations) for algebraic multigrid."""
        p = self.problem
        x = p.V.tabulate_dof_coordinates()[: p.V.dofmap.index_map.size_local, : p.dim]
        modes = []
        for k in range(p.dim):
            mode = np.zeros_like(x)
            mode[:, k] = 1.0
            modes.append(mode)
        for k in [2] if p.dim == 2 else [0, 1, 2]:
            modes.append(_cross_axis(k, x))
        vectors = []
        for mode in modes:
            vector = p.u.vector.copy()
            vector.array_w[:] = mode.reshape(-1)
            vectors.append(vector)
        for i, vector in enumerate(vectors):  # PETSc wants an orthonormal basis
            for other in vectors[:i]:
                vector.axpy(-vector.dot(other), other)
            vector.normalize()
        return PETSc.NullSpace().create(vectors=vectors, comm=p.mesh.comm)

    # -- rigid-body modes of the current configuration ---------------------------------
    def _arms(self) -> np.ndarray:
        """x - x_ref for every owned node (current positions, mm)."""
        p = self.problem
        u = p.u.x.array[: self.n_owned * p.dim].reshape(-1, p.dim)
        return self.coordinates + u - p.rigid.reference_point()

    def _modes(self) -> list[np.ndarray]:
        """Rigid-body test fields W (owned dofs): translations, then rotations e_k x (x - x_ref)."""
        dim, arms = self.problem.dim, self._arms()
        modes = []
        for k in range(dim):
            mode = np.zeros_like(arms)
            mode[:, k] = 1.0
            modes.append(mode)
        axes = [2] if dim == 2 else [0, 1, 2]
        for k in axes:
            modes.append(_cross_axis(k, arms))
        return [mode.reshape(-1) for mode in modes]

    def _allsum(self, value):
        return self.problem.mesh.comm.allreduce(value, op=MPI.SUM)

    # -- residual ----------------------------------------------------------------------
    def assemble_residual(self, load):
        """Assemble R_u (Vec, support rows zeroed), R_r (numpy) and the force scale (N)."""
        p = self.problem
        for b, form in ((self.b_bulk, self.residual_bulk), (self.b_contact, self.residual_contact)):
            with b.localForm() as local:
                local.set(0.0)
            petsc.assemble_vector(b, form)
            if b is self.b_contact:
                self.corner_contacts = p.corners.add_residual(b)
            b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        contact = self.b_contact.array_r
        G = np.array([self._allsum(float(mode @ contact)) for mode in self._modes()])
        Q_ext = load.generalized_force(p.rigid.values)
        R_r = -(Q_ext + G) + p.rigid_inertia_force(load) + self.stabilization @ (p.rigid.values - p.rigid.r_old.value)
        R_u = self.b_bulk.copy()
        R_u.axpy(1.0, self.b_contact)
        petsc.set_bc(R_u, p.bcs, scale=0.0)
        scale = max(self.b_bulk.norm(), np.linalg.norm(Q_ext), np.linalg.norm(G))
        return R_u, R_r, scale

    def norm(self, R_u, R_r) -> float:
        free = self.problem.rigid.free
        return float(np.sqrt(R_u.norm() ** 2 + np.sum(R_r[free] ** 2)))

    # -- Newton --------------------------------------------------------------------------
    def stabilize(self, factor: float) -> None:
        """Switch the contact stabilisation: a spring of stiffness E * h_contact (N/mm; rotations
        scaled by the body size squared) tying the rigid body to its last converged pose.
        `factor` scales it (0 = off). It gives a body with no contact yet a finite
        stiffness, as Abaqus' contact stabilisation does; the stepper then removes it by
        continuation (see Simulation.increment)."""
        p = self.problem
        k = float(p.constants["E"].value) * p.model.h_contact
        size = p.shape["scale"]
        scale = np.where(np.arange(len(p.rigid.names)) < p.dim, 1.0, size * size)
        self.stabilization = factor * np.diag(k * scale)

    def solve(self, load) -> int:
        """Solve one increment; returns the Newton iterations taken."""
        p, options = self.problem, self.problem.scene["solver"]
        history = []
        for iteration in range(options["max_iterations"] + 1):
            R_u, R_r, scale = self.assemble_residual(load)
            norm = self.norm(R_u, R_r)
            history.append(norm)
            if not np.isfinite(norm):
                raise NewtonFailure("residual is not finite", history)
            if norm <= options["atol"] + options["rtol"] * scale:
                return iteration
            if iteration == options["max_iterations"]:
                break
            du, dr = self.direction(load, R_u, R_r)
            self.line_search(load, du, dr, norm, history)
        raise NewtonFailure(f"no convergence in {options['max_iterations']} iterations", history)

    def direction(self, load, R_u, R_r):
        """Newton direction (du Vec, dr array) from the Schur complement."""
        p = self.problem
        n_r, free = len(p.rigid.names), p.rigid.free
        self.K.zeroEntries()
        petsc.assemble_matrix(self.K, self.jacobian, bcs=p.bcs)
        self.Kc.zeroEntries()
        petsc.assemble_matrix(self.Kc, self.jacobian_contact)
        for b, form in zip(self.kur, self.contact_dr):
            with b.localForm() as local:
                local.set(0.0)
            petsc.assemble_vector(b, form)
        p.corners.add_jacobian([self.K, self.Kc], self.kur, self.bc_dofs)
        self.K.assemble()
        self.Kc.assemble()
        for b in self.kur:
            b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)

        contact = self.b_contact.array_r.reshape(-1, p.dim)
        modes = self._modes()
        # dR_r/du rows: -(W^T Kc + C^T dW/du)
        K_ru = []
        axes = [2] if p.dim == 2 else [0, 1, 2]
        for j, mode in enumerate(modes):
            w, row = self.work[j], self.work[n_r + j]
            w.array_w[:] = mode
            self.Kc.multTranspose(w, row)
            if j >= p.dim:
                row.array_w[:] += _cross_with_axis(contact, axes[j - p.dim]).reshape(-1)
            row.scale(-1.0)
            K_ru.append(row)
        # dR_r/dr: -(W^T dC/dr + C^T dW/dr) - dQ_ext/dr + inertia
        total_contact = np.array([self._allsum(contact[:, k].sum()) for k in range(p.dim)])
        K_rr = np.zeros((n_r, n_r))
        for j, mode in enumerate(modes):
            for k in range(n_r):
                K_rr[j, k] = -self._allsum(float(mode @ self.kur[k].array_r))
        for j in range(p.dim, n_r):  # d(e_a x (x - x_ref))/dt = -e_a x dt
            K_rr[j, : p.dim] += _cross_with_axis(total_contact[None, :], axes[j - p.dim])[0]
        K_rr += (-load.generalized_force_jacobian(p.rigid.values) + p.rigid_inertia_stiffness(load)
                 + self.stabilization)

        y, du = self.work[2 * n_r], self.work[2 * n_r + 1]
        self._linear_solve(R_u, y)
        X = []
        for k in range(n_r):
            rhs = self.work[2 * n_r + 2]
            self.kur[k].copy(rhs)
            petsc.set_bc(rhs, p.bcs, scale=0.0)
            column = rhs.duplicate()
            self._linear_solve(rhs, column)
            X.append(column)
        S = K_rr - np.array([[K_ru[i].dot(X[k]) for k in range(n_r)] for i in range(n_r)])
        rhs_r = -R_r + np.array([K_ru[i].dot(y) for i in range(n_r)])
        dr = np.zeros(n_r)
        if free.any():
            dr[free] = self._rigid_step(S[np.ix_(free, free)], rhs_r[free])
        y.copy(du)
        du.scale(-1.0)
        for k in range(n_r):
            du.axpy(-dr[k], X[k])
        return du, dr

    def _rigid_step(self, S_ff, rhs) -> np.ndarray:
        """Solve S dr = rhs for the free rigid dofs inside a trust region.

        A body out of contact has no stiffness: S is regularised by 1e-9 of its own scale
        (or of E * size) and the step is capped at one contact element size h (rotations
        at h / size), so a body that must travel to meet its partner gets there in steps
        instead of leaping through it. The regularisation only shapes the step; the
        converged state solves the unregularised equations."""
        p = self.problem
        size = p.shape["scale"]
        scale = max(np.abs(np.diag(S_ff)).max(), float(p.constants["E"].value) * size)
        dr = np.linalg.solve(S_ff + 1e-9 * scale * np.eye(len(rhs)), rhs)
        length = np.abs(dr * np.where(np.arange(len(dr)) < p.dim, 1.0, size)[: len(dr)]).max()
        cap = p.model.h_contact
        return dr * min(1.0, cap / length) if length > 0 else dr

    def update_anchors(self) -> None:
        """Move each contact node's stick anchor so that -gamma_T (xi - anchor) equals the
        converged tangential traction: anchor = xi + R^T t / gamma_T. The traction per node
        is its contact force (integral terms only) over its lumped contact area."""
        p = self.problem
        force = self.b_anchor
        for vector, form in ((force, self.residual_contact), (self.area, self.area_form)):
            with vector.localForm() as local:
                local.set(0.0)
            petsc.assemble_vector(vector, form)
            vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        from femcontact.rigid_body import rotation_numpy

        with force.localForm() as f, self.area.localForm() as a:
            traction = -f.array.reshape(-1, p.dim)
            weight = a.array.reshape(-1, p.dim)[:, :1]
        traction = np.where(weight > 0, traction / np.where(weight > 0, weight, 1.0), 0.0)
        R = rotation_numpy(p.rigid.split(p.rigid.values)[1]) @ p.rigid.Q0
        gamma_t = float(p.constants["gamma_t"].value * p.constants["E"].value) / p.model.h_contact
        anchor = p.local_coordinates() + traction @ R / gamma_t
        p.history["anchor"].x.array[:] = anchor.reshape(-1)

    def _linear_solve(self, rhs, out) -> None:
        self.ksp.solve(rhs, out)
        if self.ksp.getConvergedReason() < 0:
            raise NewtonFailure(f"linear solver failed (PETSc reason {self.ksp.getConvergedReason()})", [])
        out.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def line_search(self, load, du, dr, norm, history) -> None:
        """Take the longest step of 1, 1/2, ... 1/4096 that lowers |R|; else the best found."""
        p = self.problem
        u0, r0 = p.u.vector.copy(), p.rigid.values.copy()
        best = (np.inf, 1.0)
        steps = [1.0] if not p.scene["solver"]["line_search"] else [2.0 ** -k for k in range(13)]
        for alpha in steps:
            self._update(u0, r0, du, dr, alpha)
            if len(steps) == 1:
                return
            trial = self.norm(*self.assemble_residual(load)[:2])
            if trial < (1 - 1e-4 * alpha) * norm:
                return
            best = min(best, (trial if np.isfinite(trial) else np.inf, alpha))
        self._update(u0, r0, du, dr, best[1])

    def _update(self, u0, r0, du, dr, alpha) -> None:
        p = self.problem
        u0.copy(p.u.vector)
        p.u.vector.axpy(alpha, du)
        p.u.x.scatter_forward()
        p.rigid.values[:] = r0 + alpha * dr
        p.rigid.sync()


def _cross_axis(k: int, arms: np.ndarray) -> np.ndarray:
    """e_k x arms for each row (2-D arms use k = 2, the out-of-plane axis)."""
    if arms.shape[1] == 2:
        return np.c_[-arms[:, 1], arms[:, 0]]
    e = np.zeros(3)
    e[k] = 1.0
    return np.cross(e, arms)


def _cross_with_axis(a: np.ndarray, k: int) -> np.ndarray:
    """a x e_k for each row (2-D: k = 2), the gradient of C . (e_k x d) with respect to d."""
    if a.shape[1] == 2:
        return np.c_[a[:, 1], -a[:, 0]]
    e = np.zeros(3)
    e[k] = 1.0
    return np.cross(a, e)
