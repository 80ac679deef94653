"""3-D pin-jointed truss: axial members, supports, nodal loads and rigid node sets.

Units: mm, N, N*mm, rad. A member is an axial spring of stiffness `k` (N/mm) acting in
tension and compression, stress-free in the initial geometry. A rigid node set moves
as one rigid body carried by a reference point; its six unknowns are the translation
of that point and a rotation. Two kinematics:

- linear: small displacements, equilibrium in the initial geometry (`solve_linear`);
- exact: large displacements, equilibrium in the moved geometry, Newton iterations
  with load stepping and the consistent tangent (`solve_exact`).

Both solve force control (nodal loads, and a force through a rigid set's reference
point plus a couple) and displacement control (a rigid set prescribed to move by
translation t and rotation R = Rz(thz) Ry(thy) Rx(thx) about a chosen point).
Member elongations are computed from displacements, (2 e0.du + du.du) / (l + l0),
so very stiff members (stiffness ratios of 1e8) keep their accuracy.
"""
from dataclasses import dataclass, field

import numpy as np

from femcontact.physics.rotation import rotation_numpy


def skew(v) -> np.ndarray:
    """Matrix [v]x with [v]x w = v x w."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def angles_zyx(rotation) -> np.ndarray:
    """(thx, thy, thz) in rad with rotation = Rz(thz) Ry(thy) Rx(thx); |thy| < pi/2."""
    r = rotation
    return np.array([np.arctan2(r[2, 1], r[2, 2]), np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0])),
                     np.arctan2(r[1, 0], r[0, 0])])


def rotation_vector(phi) -> np.ndarray:
    """Rotation matrix exp([phi]x) (Rodrigues) of a rotation vector phi (rad)."""
    angle = np.linalg.norm(phi)
    if angle < 1e-300:
        return np.eye(3)
    w = skew(np.asarray(phi) / angle)
    return np.eye(3) + np.sin(angle) * w + (1.0 - np.cos(angle)) * (w @ w)


@dataclass
class RigidSet:
    """Nodes moving as one rigid body carried by `point` (mm, initial position)."""
    nodes: list
    point: np.ndarray
    force: np.ndarray = field(default_factory=lambda: np.zeros(3))   # N, through the moving point
    couple: np.ndarray = field(default_factory=lambda: np.zeros(3))  # N*mm, dead couple
    motion: tuple | None = None  # prescribed (t, angles, about) or None (free)


@dataclass
class State:
    """A configuration: nodal displacements (N, 3) in mm, and per rigid set the translation
    of its reference point (mm) and its rotation matrix."""
    u: np.ndarray
    translations: list
    rotations: list


class Truss:
    """A pin-jointed truss; build it with `add_member`, `fix`, `load`, `add_rigid_set`."""

    def __init__(self, nodes):
        self.nodes = np.array(nodes, dtype=float).reshape(-1, 3)
        self.members: list[tuple[int, int, float]] = []
        self.fixed = np.zeros((len(self.nodes), 3), dtype=bool)
        self.loads = np.zeros((len(self.nodes), 3))
        self.rigid_sets: list[RigidSet] = []

    def add_member(self, i: int, j: int, k: float) -> int:
        """Axial member between nodes i and j with stiffness k (N/mm); returns its index."""
        if i == j or np.allclose(self.nodes[i], self.nodes[j]):
            raise ValueError(f"member {i}-{j} has zero length")
        self.members.append((i, j, float(k)))
        return len(self.members) - 1

    def fix(self, node: int, dofs=(0, 1, 2)) -> None:
        """Support: hold the given displacement components (0 = x, 1 = y, 2 = z) of a node."""
        self.fixed[node, list(dofs)] = True

    def load(self, node: int, force) -> None:
        """Dead nodal force (N)."""
        self.loads[node] += force

    def add_rigid_set(self, nodes, point) -> int:
        """Make `nodes` one rigid body with reference point `point` (mm); returns its index."""
        taken = {n for s in self.rigid_sets for n in s.nodes}
        if taken & set(nodes):
            raise ValueError("a node belongs to two rigid sets")
        self.rigid_sets.append(RigidSet(list(nodes), np.asarray(point, dtype=float)))
        return len(self.rigid_sets) - 1

    def load_rigid_set(self, index: int, force=(0, 0, 0), couple=(0, 0, 0)) -> None:
        """Force (N) through the set's moving reference point and a dead couple (N*mm)."""
        self.rigid_sets[index].force = np.asarray(force, dtype=float)
        self.rigid_sets[index].couple = np.asarray(couple, dtype=float)

    def prescribe(self, index: int, translation=(0, 0, 0), angles=(0, 0, 0), about=None) -> None:
        """Displacement control: the set moves by x' = p + t + R (x - p), R = Rz Ry Rx(angles),
        about the point p (mm, default its reference point)."""
        about = self.rigid_sets[index].point if about is None else np.asarray(about, dtype=float)
        self.rigid_sets[index].motion = (np.asarray(translation, float), np.asarray(angles, float), about)

    # -- unknowns ---------------------------------------------------------------------------
    def _free_nodes(self) -> np.ndarray:
        in_sets = np.zeros(len(self.nodes), dtype=bool)
        for s in self.rigid_sets:
            in_sets[s.nodes] = True
        return ~in_sets[:, None] & ~self.fixed

    def _unknowns(self):
        """Map from nodal dofs to unknowns: free nodal dofs first, then 6 per free rigid set."""
        free = self._free_nodes().ravel()
        index = np.full(free.size, -1)
        index[free] = np.arange(free.sum())
        sets, n = [], int(free.sum())
        for s in self.rigid_sets:
            sets.append(None if s.motion is not None else n)
            n += 0 if s.motion is not None else 6
        return index, sets, n

    def zero_state(self) -> State:
        return State(np.zeros_like(self.nodes), [np.zeros(3) for _ in self.rigid_sets],
                     [np.eye(3) for _ in self.rigid_sets])

    def _place_rigid_sets(self, state: State) -> None:
        """Nodal displacements of every rigid set from its translation and rotation."""
        for s, t, rot in zip(self.rigid_sets, state.translations, state.rotations):
            r0 = self.nodes[s.nodes] - s.point
            state.u[s.nodes] = t + r0 @ (rot - np.eye(3)).T

    # -- member forces and tangent ------------------------------------------------------------
    def member_forces(self, state: State, linear=False) -> np.ndarray:
        """Axial force (N, tension > 0) of every member."""
        forces = np.empty(len(self.members))
        for m, (i, j, k) in enumerate(self.members):
            e0 = self.nodes[j] - self.nodes[i]
            du = state.u[j] - state.u[i]
            l0 = np.linalg.norm(e0)
            if linear:
                forces[m] = k * (e0 @ du) / l0
            else:
                l = np.linalg.norm(e0 + du)
                forces[m] = k * (2.0 * e0 @ du + du @ du) / (l + l0)
        return forces

    def _nodal(self, state: State, linear: bool):
        """Internal nodal forces g (N, the load that holds each node) and nodal tangent K."""
        n = len(self.nodes)
        g, big_k = np.zeros((n, 3)), np.zeros((3 * n, 3 * n))
        forces = self.member_forces(state, linear)
        for (i, j, k), force in zip(self.members, forces):
            e = self.nodes[j] - self.nodes[i] + (0.0 if linear else state.u[j] - state.u[i])
            l = np.linalg.norm(e)
            unit = e / l
            km = k * np.outer(unit, unit)
            if not linear:
                km += force / l * (np.eye(3) - np.outer(unit, unit))
            g[i] -= force * unit
            g[j] += force * unit
            for a, b, sign in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
                big_k[3 * a:3 * a + 3, 3 * b:3 * b + 3] += sign * km
        return g, big_k

    def _arms(self, state: State, s_index: int, linear: bool) -> np.ndarray:
        """Vectors (mm) from a rigid set's reference point to its nodes, current geometry."""
        s = self.rigid_sets[s_index]
        r0 = self.nodes[s.nodes] - s.point
        return r0 if linear else r0 @ state.rotations[s_index].T

    def _reduce(self, state: State, linear: bool):
        """Residual (external minus internal) and tangent in the unknowns."""
        index, sets, n = self._unknowns()
        g, big_k = self._nodal(state, linear)
        t = np.zeros((big_k.shape[0], n))
        rows = np.flatnonzero(index >= 0)
        t[rows, index[rows]] = 1.0
        residual = np.zeros(n)
        residual[index[rows]] = (self.loads.ravel() - g.ravel())[rows]
        geometric = np.zeros((n, n))
        for s_index, (s, col) in enumerate(zip(self.rigid_sets, sets)):
            if col is None:
                continue
            arms = self._arms(state, s_index, linear)
            gs = g[s.nodes] - self.loads[s.nodes]
            for node, r, gi in zip(s.nodes, arms, gs):
                t[3 * node:3 * node + 3, col:col + 3] = np.eye(3)
                t[3 * node:3 * node + 3, col + 3:col + 6] = -skew(r)
                if not linear:
                    geometric[col + 3:col + 6, col + 3:col + 6] += skew(gi) @ skew(r)
            residual[col:col + 3] = s.force - gs.sum(axis=0)
            residual[col + 3:col + 6] = s.couple - np.cross(arms, gs).sum(axis=0)
        return residual, t.T @ big_k @ t + geometric, sets, index

    def _apply(self, state: State, delta, sets, index, linear: bool) -> None:
        """Add an increment of the unknowns to a state (rotations updated multiplicatively)."""
        rows = np.flatnonzero(index >= 0)
        state.u.ravel()[rows] += delta[index[rows]]
        for s_index, col in enumerate(sets):
            if col is None:
                continue
            state.translations[s_index] = state.translations[s_index] + delta[col:col + 3]
            spin = delta[col + 3:col + 6]
            rot = state.rotations[s_index]
            state.rotations[s_index] = rot + skew(spin) if linear else rotation_vector(spin) @ rot
        self._place_rigid_sets(state)

    def _prescribed(self, state: State, fraction: float, linear: bool) -> None:
        """Put every prescribed rigid set at `fraction` of its prescribed motion."""
        for s_index, s in enumerate(self.rigid_sets):
            if s.motion is None:
                continue
            t, angles, about = (np.asarray(v) for v in s.motion)
            rot = np.eye(3) + skew(fraction * angles) if linear else rotation_numpy(fraction * angles)
            state.rotations[s_index] = rot
            state.translations[s_index] = fraction * t + (rot - np.eye(3)) @ (s.point - about)
        self._place_rigid_sets(state)

    # -- solvers ----------------------------------------------------------------------------
    def solve_linear(self, refinements: int = 3) -> State:
        """Small-displacement solution; rigid-set rotations are I + [theta]x (theta small).
        The residual is re-evaluated member by member and the solution refined `refinements`
        times, which recovers the digits that assembling stiff and soft members together loses."""
        state = self.zero_state()
        self._prescribed(state, 1.0, linear=True)
        for _ in range(1 + refinements):
            residual, tangent, sets, index = self._reduce(state, linear=True)
            if residual.size:
                self._apply(state, np.linalg.solve(tangent, residual), sets, index, linear=True)
        return state

    def solve_exact(self, increments: int = 4, rtol: float = 1e-11, max_iterations: int = 25,
                    max_cuts: int = 10) -> State:
        """Large-displacement equilibrium by Newton with load stepping; the loads and the
        prescribed motions grow together in `increments` equal steps, halved on failure."""
        state, done, step, cuts = self.zero_state(), 0.0, 1.0 / increments, 0
        while done < 1.0 - 1e-12:
            target = min(1.0, done + step)
            trial = State(state.u.copy(), list(state.translations), list(state.rotations))
            if self._newton(trial, target, rtol, max_iterations):
                state, done = trial, target
                continue
            cuts += 1
            if cuts > max_cuts:
                raise RuntimeError(f"Newton failed at load fraction {target:.4g} after {max_cuts} cuts")
            step /= 2.0
        return state

    def _load_scale(self) -> float:
        """Largest applied force or couple component (N, N*mm)."""
        return max(np.abs(self.loads).max(initial=0.0),
                   max((np.abs(np.r_[s.force, s.couple]).max() for s in self.rigid_sets), default=0.0))

    def _converged(self, state: State, residual, scale: float, rtol: float) -> bool:
        """Residual below rtol times the force level, or at the round-off floor of the member
        forces (about eps k |du| per member: what stiff members cannot resolve better)."""
        if residual.size == 0:
            return True
        level, floor = scale, 0.0
        for (i, j, k), force in zip(self.members, self.member_forces(state)):
            du = np.linalg.norm(state.u[j] - state.u[i])
            level = max(level, abs(force))
            floor += (k * du) ** 2
        eps = np.finfo(float).eps
        return np.linalg.norm(residual) <= max(rtol * level, 16 * eps * np.sqrt(floor), 1e-300)

    def _newton(self, state: State, fraction: float, rtol: float, max_iterations: int) -> bool:
        """Newton iterations at a load fraction; True when the residual is converged. One more
        correction follows convergence (iterative refinement, as in `solve_linear`)."""
        self._prescribed(state, fraction, linear=False)
        saved = self.loads, [(s.force, s.couple) for s in self.rigid_sets]
        self.loads = self.loads * fraction
        for s in self.rigid_sets:
            s.force, s.couple = s.force * fraction, s.couple * fraction
        try:
            for _ in range(max_iterations):
                residual, tangent, sets, index = self._reduce(state, linear=False)
                converged = self._converged(state, residual, self._load_scale(), rtol)
                if residual.size:
                    self._apply(state, np.linalg.solve(tangent, residual), sets, index, linear=False)
                if converged:
                    return True
            return False
        finally:
            self.loads = saved[0]
            for s, (force, couple) in zip(self.rigid_sets, saved[1]):
                s.force, s.couple = force, couple

    # -- results ----------------------------------------------------------------------------
    def rigid_motion(self, state: State, index: int, about=None, linear=False):
        """(t, angles): motion of a rigid set about the point `about` (mm, default its
        reference point), x' = p + t + R (x - p), angles = (thx, thy, thz) of R = Rz Ry Rx
        (for linear states the small rotation vector)."""
        s = self.rigid_sets[index]
        about = s.point if about is None else np.asarray(about, dtype=float)
        rot = state.rotations[index]
        t = state.translations[index] - (rot - np.eye(3)) @ (s.point - about)
        if linear:
            return t, np.array([rot[2, 1], rot[0, 2], rot[1, 0]])
        return t, angles_zyx(rot)

    def holding_wrench(self, state: State, index: int, about, linear=False) -> np.ndarray:
        """(Fx, Fy, Fz, Mx, My, Mz): the load (N, N*mm) that holds a rigid set in `state`,
        moments about the fixed point `about` (mm)."""
        s = self.rigid_sets[index]
        g, _ = self._nodal(state, linear)
        gs = g[s.nodes] - self.loads[s.nodes]
        x = self.nodes[s.nodes] + (0.0 if linear else state.u[s.nodes])
        return np.r_[gs.sum(axis=0), np.cross(x - np.asarray(about, float), gs).sum(axis=0)]

    def rigid_tangent(self, state: State, index: int) -> np.ndarray:
        """6x6 tangent stiffness of a rigid set's holding wrench (exact kinematics) for small
        extra motions (translation of its moved reference point, spin), moments about that
        moved point, other free nodes condensed out. Spatial axes; N/mm, N, N*mm/rad."""
        s = self.rigid_sets[index]
        motion, s.motion = s.motion, None
        try:
            _, tangent, sets, _ = self._reduce(state, linear=False)
        finally:
            s.motion = motion
        col = sets[index]
        keep = np.r_[col:col + 6]
        rest = np.setdiff1d(np.arange(tangent.shape[0]), keep)
        k = tangent[np.ix_(keep, keep)]
        if rest.size:
            k = k - tangent[np.ix_(keep, rest)] @ np.linalg.solve(tangent[np.ix_(rest, rest)],
                                                                  tangent[np.ix_(rest, keep)])
        return k
