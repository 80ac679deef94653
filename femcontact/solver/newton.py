"""Monolithic Newton for the deformable body (u) and the rigid body (r) together.

Each iteration solves the bordered system

    [K_uu  K_ur] [du]     [R_u]
    [K_ru  K_rr] [dr] = - [R_r]

by eliminating the few rigid unknowns with a Schur complement: one solve with K_uu
(solver/linear.py: factored every iteration, or its bulk part once with a low-rank contact
update) serves the residual and the n_r columns of K_ur at once, then the small dense system
S dr = -R_r + K_ru y, S = K_rr - K_ru X, gives dr. The Jacobian is consistent: K_uu
and K_ur come from UFL derivatives of the residual, the rigid rows from the contact
vector C (N) tested with the rigid-body modes W(u, r) of the current configuration:

    R_r = -(Q_ext(r) + W^T C) + R_effects(r)      (forces N, moments N*mm)

where R_effects are the effects' own rigid-body terms (inertia M a(r), weight). The
solver calls only the problem's forms and hooks; it names no effect.

The solver takes its settings as `SolverOptions` (femcontact/config/solver.py) and the
physical scales it needs (a stiffness modulus, the contact's stiffness and element size, the
rigid body's size) from `Problem` methods. A line search (see `SchurNewton.line_search`) damps
the semismooth Newton where stick/slip or contact sets change; before it, where the options
ask for `curved_step`, a rejected full step is retried along a curved path that follows the
residual's curvature (`SchurNewton.curved_step`). A failed linear solve, a NaN, a residual that has
stopped moving (`SchurNewton._stalled`) or too many iterations raise `NewtonFailure`, which the
stepper answers by cutting the increment.
"""
import time

import numpy as np
from dolfinx import la
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

from femcontact.physics.rotation import cross_with_axis, rigid_modes
from femcontact.solver.linear import LinearSolveFailed, linear_solver

ROOT_EVALUATIONS = 12
"""Residual assemblies the line search spends at most on the root of the slope g(alpha): where g
jumps at a stick/slip switch the bracket must shrink by 2^6 and more to find the switch's band,
and each assembly costs less than the Newton iteration that would otherwise follow."""
SWITCH_EVALUATIONS = 4
"""Residual assemblies the line search spends at most on landing inside a switch (`_into_switch`)."""
FLAT_SHRINK = 1 / 64
"""Where the slope g kept its value as alpha fell (it jumps near a_lo), the next alpha's
fraction of the bracket."""
CURVE_PROBE = 1.0 / 64
"""Fraction of the Newton step at which `curved_step` measures the residual's curvature."""
SOLVE_KINDS = ("plain", "continuation", "failed")
"""How a Newton solve ended, as `SchurNewton.solves` counts them: converged without the
stabilisation spring, converged with it (the stabilised and the pseudo-transient continuation),
or failed (any kind; the stepper then tries the next way or cuts the increment)."""


class NewtonFailure(RuntimeError):
    """Newton did not converge; `history` holds the residual norms per iteration."""

    def __init__(self, message: str, history: list):
        super().__init__(f"{message}; residual history {['%.3e' % r for r in history]}")
        self.history = history


class BodyGone(NewtonFailure):
    """The rigid body travelled, without coming to rest, farther than its caller asked to follow
    it (`Simulation.pseudo_transient_solve`'s `gone`)."""


class SchurNewton:
    """Newton solver with the rigid-body unknowns condensed by a Schur complement.

    `options` (`SolverOptions`) may be replaced between solves. `time_step_stiffness` is the
    hook of a time integrator (solver/dynamics.py): None, or a callable returning the diagonal
    stiffness an implicit time step currently adds to the rigid body's equations (M / dt^2 per
    rigid dof: N/mm, N*mm/rad^2), or None while it adds none. While it returns one, the rigid step is the plain
    Newton step (that stiffness makes S regular, so a body out of contact reaches its new
    position in one step instead of one contact element at a time) and the round-off floor
    includes that of the inertia term."""

    def __init__(self, problem, options, prefix: str = "femcontact_"):
        self.problem = p = problem
        self.options = options
        self.time_step_stiffness = None
        forms, n_r = p.forms, len(p.rigid.names)
        self.Kc = petsc.create_matrix(forms.jacobian_contact)
        self.b_bulk = petsc.create_vector(forms.residual_bulk)
        self.b_contact = petsc.create_vector(forms.residual_contact)
        self.kur = {j: petsc.create_vector(form) for j, form in forms.contact_dr.items()}  # free dofs only
        self.work = [p.u.vector.copy() for _ in range(2 * n_r)]
        self.n_owned = p.V.dofmap.index_map.size_local
        self.coordinates = p.V.tabulate_dof_coordinates()[: self.n_owned, : p.dim]
        self.bc_dofs = p.support_dof_set
        self.linear = linear_solver(p, options, prefix, self._near_nullspace)
        self.stabilization = np.zeros((n_r, n_r))  # spring tying the rigid body to `tie_pose` (N/mm, N*mm)
        self.tie_pose = np.zeros(n_r)  # the pose the stabilisation spring ties the body to (mm, rad)
        self._assembled = None  # (load, u, r, residual) of the last residual assembly
        # where the solve time goes: kind (SOLVE_KINDS) -> its solves, Newton iterations and seconds
        self.solves = {kind: {"solves": 0, "iterations": 0, "seconds": 0.0} for kind in SOLVE_KINDS}
        # the communicators of the vectors and matrices this solver creates (forms give them two)
        self._comms = {c.tompi4py().py2f(): c for c in (self.b_bulk.getComm(), self.Kc.getComm())}.values()

    def release_dropped(self) -> None:
        """Destroy the PETSc objects Python has dropped (residual copies, solutions, trial
        points). petsc4py leaves them to a collective clean-up, one per communicator: without it
        every Newton iteration keeps its vectors and a run grows by about 1 MB an increment."""
        for comm in self._comms:
            PETSc.garbage_cleanup(comm)

    def _near_nullspace(self) -> PETSc.NullSpace:
        """Near-nullspace of elasticity (translations and rotations) for algebraic multigrid."""
        p = self.problem
        vectors = []
        for mode in rigid_modes(self.coordinates):
            vector = p.u.vector.copy()
            vector.array_w[:] = mode.reshape(-1)
            vectors.append(vector)
        la.orthonormalize(vectors)
        return PETSc.NullSpace().create(vectors=vectors, comm=p.mesh.comm)

    # -- rigid-body modes of the current configuration ---------------------------------
    def _arms(self) -> np.ndarray:
        """x - x_ref for every owned node (current positions, mm)."""
        p = self.problem
        u = p.u.x.array[: self.n_owned * p.dim].reshape(-1, p.dim)
        return self.coordinates + u - p.rigid.reference_point()

    def _modes(self) -> list[np.ndarray]:
        """Rigid-body test fields W (owned dofs): translations, then rotations e_k x (x - x_ref)."""
        return [mode.reshape(-1) for mode in rigid_modes(self._arms())]

    def _allsum(self, value):
        return self.problem.mesh.comm.allreduce(value, op=MPI.SUM)

    # -- residual ----------------------------------------------------------------------
    def assemble_residual(self, load):
        """Assemble R_u (Vec, support rows zeroed), R_r (numpy) and the force scale (N)."""
        p = self.problem
        for b, form in ((self.b_bulk, p.forms.residual_bulk), (self.b_contact, p.forms.residual_contact)):
            with b.localForm() as local:
                local.set(0.0)
            petsc.assemble_vector(b, form)
            if b is self.b_contact:
                p.add_contact_residual(b)
            b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        contact = self.b_contact.array_r
        G = np.array([self._allsum(float(mode @ contact)) for mode in self._modes()])
        Q_ext = load.generalized_force(p.rigid.values)
        R_r = -(Q_ext + G) + p.rigid_residual(load) + self.stabilization_load()
        R_u = self.b_bulk.copy()
        R_u.axpy(1.0, self.b_contact)
        petsc.set_bc(R_u, p.bcs, scale=0.0)
        scale = max(self.b_bulk.norm(), np.linalg.norm(Q_ext), np.linalg.norm(G))
        self._assembled = (load, p.u.x.array.copy(), p.rigid.values.copy(), (R_u, R_r, scale))
        return R_u, R_r, scale

    def current_residual(self, load):
        """`assemble_residual` at the current state, reusing the last assembly when it was
        made there (the converged state of an increment, for the outputs; the line search's
        last trial where it stops)."""
        p = self.problem
        if self._assembled is not None:
            at, u, r, residual = self._assembled
            here = at is load and np.array_equal(u, p.u.x.array) and np.array_equal(r, p.rigid.values)
            if p.mesh.comm.allreduce(here, op=MPI.LAND):  # every rank decides alike (assembly is collective)
                return residual
        return self.assemble_residual(load)

    def norm(self, R_u, R_r) -> float:
        free = self.problem.rigid.free
        return float(np.sqrt(R_u.norm() ** 2 + np.sum(R_r[free] ** 2)))

    def force_norm(self, R_u, R_r) -> float:
        """|R| with the rigid body's moment rows (N*mm) divided by its size (`Problem.body_size`),
        so every row is a force (N): what the stopping test measures. A moment's round-off is its
        forces' round-off times arms up to the body's size, so the plain |R| of a peg pressed flat
        along a wall can stall above atol while its forces have converged."""
        return self.norm(R_u, R_r / self.problem.rigid_arms)

    # -- Newton --------------------------------------------------------------------------
    def _time_step(self) -> np.ndarray | None:
        """What `time_step_stiffness` reports now (None without an integrator)."""
        return self.time_step_stiffness() if self.time_step_stiffness else None

    def roundoff(self) -> float:
        """Round-off floor of the residual (N): positions known to eps * |x| (mm) under the
        contact's stiffness (`Problem.contact_stiffness`). On fine contact meshes it exceeds
        atol, which no Newton step could then reach. Under an implicit time step
        (`time_step_stiffness`) the inertia term M (q1 - q0) / dt^2 adds its own: q1 - q0 is
        known to eps (|q1| + |q0|), and M / dt^2 grows without bound as dt shrinks."""
        p = self.problem
        floor = np.finfo(float).eps * p.extent * p.contact_stiffness()
        stiffness = self._time_step()
        if stiffness is not None:
            rigid = p.rigid
            spread = np.abs(rigid.values) + np.abs(rigid.r_old.value)
            floor += float(np.linalg.norm((np.finfo(float).eps * spread * stiffness)[rigid.free]))
        return floor

    def tolerance(self, scale: float) -> float:
        """The residual norm (N) at which Newton stops: atol + rtol * `scale` (the largest of the
        bulk, load and contact force norms, N) + the round-off floor."""
        return self.options.atol + self.options.rtol * scale + self.roundoff()

    def stabilize(self, factor: float, tie_pose=None) -> None:
        """Switch the contact stabilisation: a spring of stiffness E * h_contact (N/mm, E the
        problem's `stiffness_scale`; rotations scaled by the body size squared) tying the rigid
        body to `tie_pose` (default: its last converged pose). `factor` scales it (0 = off). It gives a body with no contact yet a
        finite stiffness, as Abaqus' contact stabilisation does; the stepper then removes it by
        continuation, or moves that pose along in pseudo time (see Simulation.increment)."""
        p = self.problem
        k = p.stiffness_scale() * p.contact_size
        self.stabilization = factor * np.diag(k * p.rigid_arms ** 2)
        self.tie_pose = p.rigid.r_old.value.copy() if tie_pose is None else np.array(tie_pose, dtype=float)

    def stabilization_load(self) -> np.ndarray:
        """The stabilisation spring's generalised force on the rigid body at the current pose
        (N, N*mm; zero when it is off)."""
        return self.stabilization @ (self.problem.rigid.values - self.tie_pose)

    def stabilization_force(self) -> float:
        """The stabilisation spring's load on the rigid body at the current pose: |force| plus
        |moment| over the body size (N)."""
        p, load = self.problem, self.stabilization_load()
        return float(np.linalg.norm(load[: p.dim]) + np.linalg.norm(load[p.dim:]) / p.body_size)

    def solve(self, load, stiff_start: bool = False) -> int:
        """Solve one increment; returns the Newton iterations taken. `stiff_start`: fail at once
        when the rigid body floats where the increment starts (no stiffness in any free
        direction: no contact active, no support), so that the first step goes to the
        trust-region cap along the load; from there plain Newton can settle in another
        configuration (a 3-D peg rolled about the line through its two contacts and jammed
        across the hole). Each solve is counted in `solves` by how it ended."""
        start = time.perf_counter()
        kind = "continuation" if np.any(self.stabilization) else "plain"
        try:
            iterations = self._iterate(load, stiff_start)
        except NewtonFailure as failure:
            self._count("failed", max(len(failure.history) - 1, 0), start)
            raise
        self._count(kind, iterations, start)
        return iterations

    def _count(self, kind: str, iterations: int, start: float) -> None:
        counts = self.solves[kind]
        counts["solves"] += 1
        counts["iterations"] += iterations
        counts["seconds"] += time.perf_counter() - start

    def _iterate(self, load, stiff_start: bool) -> int:
        """The Newton iterations of `solve`."""
        options = self.options
        history = []
        capped = None  # the last rigid step, if it was held at the trust-region cap
        residual = self.assemble_residual(load)
        for iteration in range(options.max_iterations + 1):
            self.release_dropped()
            R_u, R_r, scale = residual
            norm = self.norm(R_u, R_r)
            history.append(norm)
            if not np.isfinite(norm):
                raise NewtonFailure("residual is not finite", history)
            if self.force_norm(R_u, R_r) <= self.tolerance(scale):
                return iteration
            if self._stalled(history):
                raise NewtonFailure(f"no progress: |R| changed by less than {options.stall_change:g} of itself "
                                    f"in {options.stall_iterations} iterations in a row", history)
            if iteration == options.max_iterations:
                break
            du, dr = self.direction(load, R_u, R_r)
            if stiff_start and iteration == 0 and self._floating():
                raise NewtonFailure("the rigid body has no stiffness where the increment starts "
                                    "(no contact active)", history)
            if self._at_cap(dr):
                if capped is not None and capped @ dr < 0:
                    raise NewtonFailure("the rigid step swings back and forth at the trust-region cap "
                                        "(the body has no stiffness in some direction)", history)
                capped = dr
            else:
                capped = None
            residual = self.line_search(load, du, dr, (R_u, R_r, scale))
        raise NewtonFailure(f"no convergence in {options.max_iterations} iterations", history)

    def _stalled(self, history) -> bool:
        """Whether |R| moved by less than `stall_change` of itself in each of the last
        `stall_iterations` iterations: the line search keeps finding no descent (Newton cycling
        between contact states, or creeping along a kink), and the iterations left to
        `max_iterations` would not converge either (measured in docs/stability.md, "A Newton
        solve that stalls")."""
        n, change = self.options.stall_iterations, self.options.stall_change
        last = history[-n - 1:]
        return len(last) == n + 1 and all(abs(b - a) <= change * a for a, b in zip(last, last[1:]))

    def direction(self, load, R_u, R_r):
        """Newton direction (du Vec, dr array) from the Schur complement."""
        p = self.problem
        n_r, free = len(p.rigid.names), np.flatnonzero(p.rigid.free)  # held and prescribed dofs are no unknowns
        self.Kc.zeroEntries()
        petsc.assemble_matrix(self.Kc, p.forms.jacobian_contact)
        for b, form in zip(self.kur.values(), p.forms.contact_dr.values()):
            with b.localForm() as local:
                local.set(0.0)
            petsc.assemble_vector(b, form)
        p.add_contact_jacobian([self.Kc] + self.linear.begin(), self.kur, self.bc_dofs)
        self.Kc.assemble()
        for b in self.kur.values():
            b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        try:
            self.linear.factor(self.Kc)
        except LinearSolveFailed as error:
            raise NewtonFailure(str(error), []) from None

        contact = self.b_contact.array_r.reshape(-1, p.dim)
        modes = self._modes()
        # dR_r/du rows of the free dofs: -(W^T Kc + C^T dW/du)
        K_ru = []
        axes = [2] if p.dim == 2 else [0, 1, 2]
        for j in free:
            w, row = self.work[j], self.work[n_r + j]
            w.array_w[:] = modes[j]
            self.Kc.multTranspose(w, row)
            if j >= p.dim:
                row.array_w[:] += cross_with_axis(contact, axes[j - p.dim]).reshape(-1)
            row.scale(-1.0)
            K_ru.append(row)
        # dR_r/dr: -(W^T dC/dr + C^T dW/dr) - dQ_ext/dr + the effects' rigid stiffness
        total_contact = np.array([self._allsum(contact[:, k].sum()) for k in range(p.dim)])
        K_rr = np.zeros((n_r, n_r))
        for j in free:
            for k in free:
                K_rr[j, k] = -self._allsum(float(modes[j] @ self.kur[k].array_r))
        for j in range(p.dim, n_r):  # d(e_a x (x - x_ref))/dt = -e_a x dt
            K_rr[j, : p.dim] += cross_with_axis(total_contact[None, :], axes[j - p.dim])[0]
        K_rr += -load.generalized_force_jacobian(p.rigid.values) + p.rigid_stiffness(load) + self.stabilization

        columns = []
        for k in free:
            rhs = self.kur[k].copy()
            petsc.set_bc(rhs, p.bcs, scale=0.0)
            columns.append(rhs)
        try:
            y, *X = self.linear.solve([R_u] + columns)
        except LinearSolveFailed as error:
            raise NewtonFailure(str(error), []) from None
        S_ff = K_rr[np.ix_(free, free)] - np.array([[row.dot(x) for x in X] for row in K_ru]).reshape(len(free), len(free))
        dr, shifted = self._condensed_step(K_ru, S_ff, y, R_r)
        self._factored = (K_ru, X, S_ff, shifted)
        return self._assemble_step(y, X, dr[free]), dr

    def _condensed_step(self, K_ru, S_ff, y, R_r, shifted: bool | None = None) -> tuple[np.ndarray, bool]:
        """The rigid step dr from S dr = -R_r + K_ru y (free dofs, K_ru their rows; see
        `_rigid_step`), and whether S was shifted. `shifted=None`: shifted only where the plain
        step meets no stiffness."""
        free = self.problem.rigid.free
        dr = np.zeros(len(free))
        if free.any():
            rhs_r = -R_r[free] + np.array([row.dot(y) for row in K_ru])
            dr[free] = self._rigid_step(S_ff, rhs_r, shifted=bool(shifted))
            if shifted is None:
                shifted = bool(dr[free] @ S_ff @ dr[free] <= 0)  # no stiffness along the step
                if shifted:
                    dr[free] = self._rigid_step(S_ff, rhs_r, shifted=True)
        return dr, bool(shifted)

    @staticmethod
    def _assemble_step(y, X, dr_free):
        """du = -(y + X dr) (X the free dofs' columns; y is overwritten)."""
        du = y
        du.scale(-1.0)
        for x, d in zip(X, dr_free):
            du.axpy(-d, x)
        return du

    def correction(self, R_u, R_r):
        """Second-order correction: the Newton step for the residual (R_u, R_r) of a trial point
        with the Jacobian already factored for the direction (one more solve, no factorisation)."""
        K_ru, X, S_ff, shifted = self._factored
        try:
            y = self.linear.solve([R_u])[0]
        except LinearSolveFailed:
            return None
        dr, _ = self._condensed_step(K_ru, S_ff, y, R_r, shifted)
        return self._assemble_step(y, X, dr[self.problem.rigid.free]), dr

    def _rigid_step(self, S_ff, rhs, shifted: bool = False) -> np.ndarray:
        """Solve S dr = rhs for the free rigid dofs inside a trust region.

        A body out of contact has no stiffness: S is regularised by 1e-9 of its own scale
        (or of E * size, E the problem's `stiffness_scale`). A body pivoting on a contact under
        load can have a negative one (the moment of the contact force as the body turns; friction makes S unsymmetric):
        where the step meets no positive stiffness (dr . S dr <= 0) it leads uphill, away
        from equilibrium, and `shifted` lifts the spectrum of S's symmetric part to that
        floor, so the step goes downhill (modified Newton). The step is capped at one
        contact element size h (rotations at h / size), so a body that must travel to meet
        its partner gets there in steps instead of leaping through it. Regularisation and
        shift only shape the step; the converged state solves the unmodified equations. Under
        an implicit time step (`time_step_stiffness`) S is regular: the plain step."""
        if self._time_step() is not None:
            return np.linalg.solve(S_ff, rhs)
        p = self.problem
        floor = self._stiffness_floor(S_ff)
        lowest = np.linalg.eigvalsh(0.5 * (S_ff + S_ff.T)).min() if shifted else floor
        dr = np.linalg.solve(S_ff + max(floor, floor - lowest) * np.eye(len(rhs)), rhs)
        length = np.abs(dr * p.rigid_arms[p.rigid.free]).max()
        cap = p.contact_size
        return dr * min(1.0, cap / length) if length > 0 else dr

    def _stiffness_floor(self, S_ff) -> float:
        """The stiffness below which S counts as none: 1e-9 of its own scale, or of E * size
        (E the problem's `stiffness_scale`) for a body without any."""
        p = self.problem
        return 1e-9 * max(np.abs(np.diag(S_ff)).max(), p.stiffness_scale() * p.body_size)

    def _floating(self) -> bool:
        """Whether the last direction's condensed rigid stiffness S is nil in every free
        direction (below `_stiffness_floor`)."""
        S_ff = self._factored[2]
        return bool(S_ff.size) and bool(np.abs(np.linalg.eigvals(S_ff)).max() <= self._stiffness_floor(S_ff))

    def _at_cap(self, dr) -> bool:
        """Whether the rigid step is as long as `_rigid_step` allows (one contact element size)."""
        p = self.problem
        return bool(p.rigid_length(dr) >= (1 - 1e-9) * p.contact_size)

    def line_search(self, load, du, dr, residual):
        """Step along (du, dr); returns the residual (R_u, R_r, scale) where it stops.

        The full step is taken when it lowers |R| (one assembly, reused by the next
        iteration). When it does not and the options ask for it (`curved_step`), the
        curved step (`curved_step`: two assemblies and one solve with the factor at hand) is
        tried. When that fails too but the step overshoots along the direction, that is the
        directional derivative g(alpha) = R(alpha) . (du, dr) (N*mm, the slope of the energy
        for a potential problem) turns from negative to positive, the step stops near the root
        of g (|g| <= |g(0)| / 2, at most ROOT_EVALUATIONS assemblies; each trial the root of a
        quadratic with Newton's slope -g(0), from 0 or, where g is still on its line at a_lo,
        from a_lo: the contact's kink lies beyond it): a semismooth Newton step linearised on
        too few contact nodes (a cold contact set, a growing contact zone) drives the body past
        equilibrium into a far too large contact set, which the following iterations could
        only shed a few nodes at a time; stopping at the root approaches the contact set from
        inside. Failing both, the longest of 1/2, 1/4, ... 1/4096 that lowers |R| (else the
        best found), carried on into the switch that stopped the longer one (`_into_switch`)."""
        p = self.problem
        norm = self.norm(*residual[:2])
        u0, r0 = p.u.vector.copy(), p.rigid.values.copy()
        self._update(u0, r0, du, dr, 1.0)
        trial = full = self.assemble_residual(load)
        if not self.options.line_search:
            return trial
        trial_norm = self.norm(*trial[:2])
        if trial_norm < (1 - 1e-4) * norm:
            return trial
        curved = self.curved_step(load, u0, r0, du, dr, residual, norm) if self.options.curved_step else None
        if curved is not None:
            return curved
        g0, g1 = self._slope(residual, du, dr), self._slope(trial, du, dr)
        if g0 < 0 < g1 and np.isfinite(g1):
            a_lo, a_hi, (a, g), flat, level = 0.0, 1.0, (1.0, g1), False, False
            g_lo, g_hi = g0, g1
            for _ in range(ROOT_EVALUATIONS):
                if level:  # g stays level below the jump: bisect the bracket
                    alpha = 0.5 * (a_lo + a_hi)
                elif flat:  # g kept its value as alpha fell: it jumps (a stick/slip switch) near a_lo
                    alpha = a_lo + FLAT_SHRINK * (a_hi - a_lo)
                else:
                    alpha = self._slope_root(g0, (a, g), (a_lo, g_lo), (a_hi, g_hi))
                self._update(u0, r0, du, dr, alpha)
                trial = self.assemble_residual(load)
                previous, (a, g) = g, (alpha, self._slope(trial, du, dr))
                flat = 0 < g and abs(g - previous) <= 0.1 * (g - g0)
                if not np.isfinite(g):
                    break
                if abs(g) <= 0.5 * abs(g0):
                    return trial
                if g < 0:
                    # aimed at the root, g came less than a tenth of the way from g_lo to it: no
                    # curvature below the jump to interpolate (a body turning freely until a contact
                    # closes), so the quadratic's root would creep up from a_lo
                    level = level or g - g_lo < 0.1 * -g_lo
                    a_lo, g_lo = alpha, g
                else:
                    a_hi, g_hi = alpha, g
            if a_lo > 0:
                self._update(u0, r0, du, dr, a_lo)
                return self.current_residual(load)
        best = (trial_norm if np.isfinite(trial_norm) else np.inf, 1.0)
        rejected = (1.0, full)
        for alpha in [2.0 ** -k for k in range(1, 13)]:
            self._update(u0, r0, du, dr, alpha)
            trial = self.assemble_residual(load)
            trial_norm = self.norm(*trial[:2])
            if trial_norm < (1 - 1e-4 * alpha) * norm:
                return self._into_switch(load, u0, r0, du, dr, (alpha, trial), rejected)
            rejected = (alpha, trial)
            best = min(best, (trial_norm if np.isfinite(trial_norm) else np.inf, alpha))
        self._update(u0, r0, du, dr, best[1])
        return self.current_residual(load)

    @staticmethod
    def _slope_root(g0, last, low, high) -> float:
        """The next trial of the slope's root search inside the bracket (a_lo, a_hi): the root of the
        quadratic with g(0) = g0 and Newton's g'(0) = -g0 through the last trial (a, g); where g is
        still g0's line at a_lo, the same quadratic from (a_lo, g_lo) to (a_hi, g_hi); else the
        bracket's middle."""
        (a, g), (a_lo, g_lo), (a_hi, g_hi) = last, low, high
        c = (g - g0 + g0 * a) / (a * a)
        if c > 0:
            alpha = (g0 + np.sqrt(g0 * g0 - 4 * c * g0)) / (2 * c)
        else:
            span = a_hi - a_lo
            c = (g_hi - g_lo + g0 * span) / (span * span)
            alpha = a_lo + (g0 + np.sqrt(g0 * g0 - 4 * c * g_lo)) / (2 * c) if c > 0 else -1.0
        return alpha if a_lo < alpha < a_hi else 0.5 * (a_lo + a_hi)

    def _into_switch(self, load, u0, r0, du, dr, accepted, rejected):
        """From the halving's accepted (alpha_lo, R_lo) and the rejected (alpha_hi, R_hi) just above
        it: where R jumps between them (a node switching between stick and slip, or into
        contact, across a band of the penalty's stiffness: micrometres or less) and the jump
        carries R through its least norm, that is h = R . (R_hi - R_lo) turns from negative to
        positive, the residual is least inside the band, where the switching node is stuck or
        touching and the next Jacobian sees it. Otherwise each iteration lands just short of the
        switch, ever closer, and never crosses it. Illinois regula falsi on h
        (at most SWITCH_EVALUATIONS assemblies); returns the residual of least norm met, the
        state left there."""
        free = self.problem.rigid.free
        (a_lo, R_lo), (a_hi, R_hi) = accepted, rejected
        jump_u = R_hi[0].copy()
        jump_u.axpy(-1.0, R_lo[0])
        jump_r = (R_hi[1] - R_lo[1])[free]

        def h(residual) -> float:
            return float(residual[0].dot(jump_u) + residual[1][free] @ jump_r)

        h_lo, h_hi = h(R_lo), h(R_hi)
        if not h_lo < 0 < h_hi:
            jump_u.destroy()
            return R_lo
        norm_lo = self.norm(*R_lo[:2])
        best = (norm_lo, a_lo)
        replaced = None  # the end replaced last ("lo", "hi"): Illinois halves the other's h
        for _ in range(SWITCH_EVALUATIONS):
            alpha = a_lo + (a_hi - a_lo) * h_lo / (h_lo - h_hi)
            if not a_lo < alpha < a_hi:
                alpha = 0.5 * (a_lo + a_hi)
            self._update(u0, r0, du, dr, alpha)
            trial = self.assemble_residual(load)
            norm, value = self.norm(*trial[:2]), h(trial)
            if not np.isfinite(norm):
                break
            if norm < best[0]:
                best = (norm, alpha)
            if norm <= 0.5 * norm_lo:
                break
            if value < 0:
                h_hi *= 0.5 if replaced == "lo" else 1.0
                a_lo, h_lo, replaced = alpha, value, "lo"
            else:
                h_lo *= 0.5 if replaced == "hi" else 1.0
                a_hi, h_hi, replaced = alpha, value, "hi"
        jump_u.destroy()
        self._update(u0, r0, du, dr, best[1])
        return self.current_residual(load)

    def curved_step(self, load, u0, r0, du, dr, residual, norm):
        """Follow the residual's curvature along the Newton direction d (geodesic acceleration):
        R(x + a d) = (1 - a) R_0 + a^2 Q + O(a^3), Q estimated from one residual at a = h =
        CURVE_PROBE; the path x + a d + a^2 c with J c = -Q cancels the quadratic term. It keeps
        a rigid body that slides over a contact node on its curved surface (a rounded rim) on
        that surface: the straight step leaves it by s^2 / (2 rho) (s the sliding, rho the radius),
        which exceeds the contact's penetration (nanometres under the stiff Nitsche/penalty
        term) long before s reaches the micrometres a step needs, so straight steps either lose
        the contact or are cut to a fraction of a micrometre. Returns the residual at the first of
        a = 1, 1/2 on the path that lowers |R| below `norm` = |R_0| (the state left there), else None."""
        h = CURVE_PROBE
        self._update(u0, r0, du, dr, h)
        R_u, R_r, _ = self.assemble_residual(load)
        R_u.axpy(-(1 - h), residual[0])
        R_u.scale(1 / h ** 2)
        step = self.correction(R_u, (R_r - (1 - h) * residual[1]) / h ** 2)
        R_u.destroy()
        if step is None:
            return None
        for alpha in (1.0, 0.5):
            self._update(u0, r0, du, dr, alpha, curve=step)
            trial = self.assemble_residual(load)
            if self.norm(*trial[:2]) < (1 - 1e-4 * alpha) * norm:
                return trial
        return None

    def _slope(self, residual, du, dr) -> float:
        """R . (du, dr) over the free unknowns (N*mm)."""
        R_u, R_r, _ = residual
        free = self.problem.rigid.free
        return float(R_u.dot(du) + R_r[free] @ dr[free])

    def _update(self, u0, r0, du, dr, alpha, curve=None) -> None:
        """The state (u0, r0) + alpha (du, dr), plus alpha^2 (dc, dr_c) along a `curve` (dc, dr_c)."""
        p = self.problem
        u0.copy(p.u.vector)
        p.u.vector.axpy(alpha, du)
        r = r0 + alpha * dr
        if curve is not None:
            p.u.vector.axpy(alpha * alpha, curve[0])
            r = r + alpha * alpha * curve[1]
        p.u.x.scatter_forward()
        p.rigid.values[:] = r
        p.rigid.sync()

