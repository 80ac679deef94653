"""Sharp corners of a rigid body against the deformable surface (2-D, P1; 3-D rims, P1).

The contact integral sees the rigid body only through its signed distance, which is
right where a corner of the deformable body presses a rigid face, but blind where a
sharp rigid corner presses a deformable face: at the micrometre penetrations of these
loads no mesh node lies inside the corner. Each sharp corner of the rigid body is
therefore also a slave point of a node-to-segment element against the deformable
contact surface (the two-pass idea of engineering codes): penalty normal force
f_n = kappa [-g]_+ with kappa = gamma * E (N/mm per mm of thickness, the stiffness a
contact node gets from the Nitsche term), and, with friction, a Coulomb return map
on the tangential force with the slip measured relative to the surface's material
point. The force enters the contact vector C at the segment's two nodes, so the
rigid-body rows of the Newton system follow from C as for the integral terms. The
element's Jacobian is taken by central differences with the contact state frozen.

3-D (`RimPoints`): the sharp circular rims of a rigid cylinder (peg tip and top) are
sampled by RIM_POINTS points; each is the slave of a node-to-triangle element against
the owned contact facets (barycentric projection, outward facet normal), with the
penalty kappa = gamma * E * (rim length per point) (N/mm) and the same Coulomb return
map on a tangential force vector in the facet's plane. On a facet of a round hole's
wall the gap is measured to the exact cylinder the flat facet approximates (a flat facet
protrudes into the hole by up to h^2 / 8R, microns, comparable to the clearances),
consistently with the nodal contact rule, whose nodes lie on the cylinder.
"""
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


def corner_points(rigid: dict) -> np.ndarray:
    """Sharp corners of a 2-D rectangle in its shape frame about the reference point."""
    if rigid["shape"] != "rectangle" or rigid["corner_radius"] > 0:
        return np.zeros((0, 2))
    w, h = rigid["half_width"], rigid["length"] / 2
    return np.array([[-w, -h], [w, -h], [w, h], [-w, h]])


class RigidCorners:
    """Node-to-segment contact of the rigid body's sharp corners (2-D, P1); in 3-D the
    node-to-triangle contact of points on the rims of a rigid cylinder (`RimPoints`)."""

    def __new__(cls, problem):
        if cls is RigidCorners and problem.dim == 3 and RIM_CONTACT:
            return super().__new__(RimPoints)
        return super().__new__(cls)

    def __init__(self, problem):
        self.problem = p = problem
        self.points = corner_points(p.model.rigid) if p.dim == 2 and p.scene["mesh"]["degree"] == 1 else np.zeros((0, 2))
        self.friction = "friction" in p.effects
        self.segments = self._segments() if len(self.points) else np.zeros((0, 3), dtype=np.int32)
        self.search = 4 * p.model.h_contact
        n = len(self.points)
        self.tangential_old = np.zeros(n)
        self.tangential = np.zeros(n)
        self.corner_old = np.array([p.rigid.place(pt + _tip(p)) for pt in self.points]) if n else np.zeros((0, 2))
        self.u_old = p.u.x.array.copy()
        self.active = np.zeros(n, dtype=bool)

    def _segments(self) -> np.ndarray:
        """Owned contact facets as rows (node a, node b, opposite node) of V's block dofs."""
        p = self.problem
        mesh, tdim = p.mesh, p.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        mesh.topology.create_connectivity(tdim, tdim - 1)
        f2c, c2f = mesh.topology.connectivity(tdim - 1, tdim), mesh.topology.connectivity(tdim, tdim - 1)
        n_cells = mesh.topology.index_map(tdim).size_local
        rows = []
        for name in p.model.contact_facets:
            for facet in p.model.facet_tags.find(p.model.facets[name]):
                cell = f2c.links(facet)[0]
                if cell >= n_cells:
                    continue
                local = int(np.where(c2f.links(cell) == facet)[0][0])
                dofs = p.V.dofmap.cell_dofs(cell)
                rows.append([dofs[(local + 1) % 3], dofs[(local + 2) % 3], dofs[local]])
        return np.array(rows, dtype=np.int32).reshape(-1, 3)

    # -- the element ------------------------------------------------------------------
    def _force(self, k: int, corner: np.ndarray, xa, xb, xc, s_fixed=None, state=None):
        """Force on the rigid corner (N) and the segment parameter for one corner."""
        p = self.problem
        edge = xb - xa
        s = np.clip((corner - xa) @ edge / (edge @ edge), 0.0, 1.0) if s_fixed is None else s_fixed
        normal = np.array([edge[1], -edge[0]]) / np.linalg.norm(edge)
        if normal @ (xa - xc) < 0:
            normal = -normal  # outward from the deformable body
        point = xa + s * edge
        gap = (corner - point) @ normal
        kappa = float(p.constants["gamma"].value * p.constants["E"].value)
        active = gap < 0 if state is None else state[0]
        f_n = kappa * max(-gap, 0.0) if state is None else kappa * (-gap) * active
        force = f_n * normal
        f_t = 0.0
        if self.friction and active:
            tangent = np.array([-normal[1], normal[0]])
            xa0, xb0 = self._old_segment
            slip = (corner - self.corner_old[k]) - (point - (xa0 + s * (xb0 - xa0)))
            kappa_t = float(p.constants["gamma_t"].value * p.constants["E"].value)
            trial = self.tangential_old[k] - kappa_t * (slip @ tangent)
            bound = float(p.constants["mu"].value) * f_n
            stick = abs(trial) <= bound if state is None else state[1]
            f_t = trial if stick else np.sign(trial if state is None else state[2]) * bound
            force = force + f_t * tangent
            return force, s, gap, (active, stick, np.sign(trial)), f_t
        return force, s, gap, (active, True, 0.0), f_t

    def _find(self, corner: np.ndarray, u: np.ndarray):
        """Best segment on this rank: (distance, row) with the corner projecting inside it."""
        if not len(self.segments):
            return np.inf, -1
        x = self.coordinates + u.reshape(-1, 2)
        xa, xb = x[self.segments[:, 0]], x[self.segments[:, 1]]
        edge = xb - xa
        length2 = np.einsum("ij,ij->i", edge, edge)
        t = np.einsum("ij,ij->i", corner - xa, edge) / length2
        distance = np.abs(np.cross(edge, corner - xa)) / np.sqrt(length2)
        distance[(t < -1e-9) | (t > 1 + 1e-9) | (distance > self.search)] = np.inf
        row = int(np.argmin(distance))
        return (float(distance[row]), row) if np.isfinite(distance[row]) else (np.inf, -1)

    def contributions(self, with_jacobian: bool):
        """Per active corner on this rank: (dofs (4,), C entries (4,), dC/du (4x4), dC/dr (4 x n_r))."""
        p = self.problem
        self.coordinates = p.V.tabulate_dof_coordinates()[:, :2]
        u = p.u.x.array
        comm = p.mesh.comm
        out = []
        for k, point in enumerate(self.points):
            corner = p.rigid.place(point + _tip(p))
            distance, row = self._find(corner, u)
            owner = int(np.argmin(comm.allgather(distance)))
            self.active[k] = False
            if comm.rank != owner or row < 0:
                continue
            a, b, c = self.segments[row]
            self._old_segment = (self.coordinates[a] + self.u_old[2 * a: 2 * a + 2],
                                 self.coordinates[b] + self.u_old[2 * b: 2 * b + 2])
            xa, xb, xc = (self.coordinates[i] + u[2 * i: 2 * i + 2] for i in (a, b, c))
            force, s, gap, state, f_t = self._force(k, corner, xa, xb, xc)
            if not state[0]:
                continue
            self.active[k] = True
            self.tangential[k] = f_t
            dofs = np.array([2 * a, 2 * a + 1, 2 * b, 2 * b + 1], dtype=np.int32)
            entries = np.r_[(1 - s) * force, s * force]
            dC_du = dC_dr = None
            if with_jacobian:
                dC_du, dC_dr = self._derivatives(k, point, (a, b, c), state)
            out.append((dofs, entries, dC_du, dC_dr))
        active = comm.allreduce(int(self.active.sum()), op=MPI.SUM)
        return out, active

    def _derivatives(self, k, point, nodes, state, h=1e-9):
        """Central differences of the C entries in the 4 segment dofs and the rigid dofs."""
        p = self.problem
        a, b, c = nodes
        base_u = p.u.x.array
        x = {i: self.coordinates[i] + base_u[2 * i: 2 * i + 2] for i in nodes}
        r0 = p.rigid.values.copy()

        def entries(dx_a, dx_b, r):
            corner = p.rigid.place(point + _tip(p), r)
            force, s, *_ = self._force(k, corner, x[a] + dx_a, x[b] + dx_b, x[c], state=state)
            return np.r_[(1 - s) * force, s * force]

        dC_du = np.zeros((4, 4))
        for j in range(4):
            e = np.zeros(4)
            e[j] = h
            dC_du[:, j] = (entries(e[:2], e[2:], r0) - entries(-e[:2], -e[2:], r0)) / (2 * h)
        dC_dr = np.zeros((4, len(r0)))
        for j in range(len(r0)):
            e = np.zeros(len(r0))
            e[j] = h
            dC_dr[:, j] = (entries(0, 0, r0 + e) - entries(0, 0, r0 - e)) / (2 * h)
        return dC_du, dC_dr

    # -- assembly into the Newton system ------------------------------------------------
    def add_residual(self, vector: PETSc.Vec) -> int:
        """Add the corners' C entries to the contact vector's local form (before ghost update)."""
        contributions, active = self.contributions(with_jacobian=False)
        with vector.localForm() as local:
            for dofs, entries, _, _ in contributions:
                local.array[dofs] += entries
        return active

    def add_jacobian(self, matrices, kur, bc_dofs: set) -> None:
        """Add dC/du to each matrix (local indices) and dC/dr to the kur vectors' local forms."""
        contributions, _ = self.contributions(with_jacobian=True)
        for matrix in matrices:
            matrix.assemblyBegin(PETSc.Mat.AssemblyType.FLUSH)
            matrix.assemblyEnd(PETSc.Mat.AssemblyType.FLUSH)
        for dofs, _, dC_du, dC_dr in contributions:
            keep = np.array([d not in bc_dofs for d in dofs])
            rows = dofs[keep]
            for matrix in matrices:
                matrix.setValuesLocal(rows, rows, dC_du[np.ix_(keep, keep)], addv=PETSc.InsertMode.ADD_VALUES)
            for j, vector in enumerate(kur):
                with vector.localForm() as local:
                    local.array[dofs] += dC_dr[:, j]

    def commit(self) -> None:
        p = self.problem
        self.tangential_old[:] = np.where(self.active, self.tangential, 0.0)
        self.corner_old = np.array([p.rigid.place(pt + _tip(p)) for pt in self.points]).reshape(-1, 2)
        self.u_old = p.u.x.array.copy()


RIM_CONTACT = False
"""3-D rim points are off: with them the wedging scene's load step cycles (Newton stalls at
a residual ~5 N between two active sets of rim points, docs/wedging_3d.md); without them
the rim is seen when the wall nodes next to it touch the peg's side (an error in the
contact point of under an element size)."""
RIM_POINTS = 128  # sample points on each rim of a 3-D cylinder (the contact point at phi = 0 included)


def rim_points(rigid: dict, points: int = RIM_POINTS) -> np.ndarray:
    """Points on the sharp rims (tip and top) of a 3-D cylinder about its reference point."""
    if rigid["shape"] != "cylinder" or rigid["corner_radius"] > 0:
        return np.zeros((0, 3))
    R, h = rigid["radius"], rigid["length"] / 2
    phi = 2 * np.pi * np.arange(points) / points
    ring = np.c_[R * np.cos(phi), R * np.sin(phi)]
    return np.vstack([np.c_[ring, np.full(points, -h)], np.c_[ring, np.full(points, h)]])


class RimPoints(RigidCorners):
    """Node-to-triangle contact of points on the rims of a rigid cylinder (3-D, P1)."""

    def __init__(self, problem):
        self.problem = p = problem
        rigid = p.model.rigid
        self.points = rim_points(rigid) if p.scene["mesh"]["degree"] == 1 else np.zeros((0, 3))
        self.friction = "friction" in p.effects
        self.arc = 2 * np.pi * rigid.get("radius", 0.0) / RIM_POINTS  # rim length per point (mm)
        self.segments, self.curved = self._segments() if len(self.points) else (np.zeros((0, 4), np.int32), None)
        self.search = 4 * p.model.h_contact
        self.wall_radius = p.scene["hole"]["width"] / 2 if p.scene["geometry"] == "peg_in_hole" else None
        n = len(self.points)
        self.tangential_old = np.zeros((n, 3))
        self.tangential = np.zeros((n, 3))
        self.corner_old = np.array([p.rigid.place(pt + _tip(p)) for pt in self.points]).reshape(-1, 3)
        self.u_old = p.u.x.array.copy()
        self.active = np.zeros(n, dtype=bool)

    def _segments(self):
        """Owned contact facets as rows (3 facet nodes, opposite node) of V's block dofs, and
        whether each lies on a round hole's wall (the tag `hole_wall`)."""
        p = self.problem
        mesh, tdim = p.mesh, p.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        mesh.topology.create_connectivity(tdim, tdim - 1)
        f2c, c2f = mesh.topology.connectivity(tdim - 1, tdim), mesh.topology.connectivity(tdim, tdim - 1)
        n_cells = mesh.topology.index_map(tdim).size_local
        rows, curved = [], []
        for name in p.model.contact_facets:
            for facet in p.model.facet_tags.find(p.model.facets[name]):
                cell = f2c.links(facet)[0]
                if cell >= n_cells:
                    continue
                local = int(np.where(c2f.links(cell) == facet)[0][0])  # facet i is opposite vertex i
                dofs = p.V.dofmap.cell_dofs(cell)
                rows.append([dofs[(local + k) % 4] for k in (1, 2, 3)] + [dofs[local]])
                curved.append(name == "hole_wall")
        return np.array(rows, dtype=np.int32).reshape(-1, 4), np.array(curved, dtype=bool)

    def _x(self, i, u):
        return self.coordinates[i] + u[3 * i: 3 * i + 3]

    def _sag(self, row, s, t) -> float:
        """How far the facet's point (s, t) protrudes into the round hole (mm; 0 off the wall)."""
        if self.wall_radius is None or not self.curved[row]:
            return 0.0
        a, b, c, _ = self.segments[row]
        X = self.coordinates[a] + s * (self.coordinates[b] - self.coordinates[a]) + t * (self.coordinates[c] - self.coordinates[a])
        return self.wall_radius - float(np.hypot(X[0], X[1]))

    def _force(self, k, corner, xa, xb, xc, xo, sag_of=None, st_fixed=None, state=None):
        """Force on the rim point (N), its facet coordinates (s, t), gap, state, tangential force."""
        p = self.problem
        e1, e2 = xb - xa, xc - xa
        normal = np.cross(e1, e2)
        normal /= np.linalg.norm(normal)
        if normal @ (xa - xo) < 0:
            normal = -normal  # outward from the deformable body
        if st_fixed is None:
            G = np.array([[e1 @ e1, e1 @ e2], [e1 @ e2, e2 @ e2]])
            s, t = np.linalg.solve(G, [e1 @ (corner - xa), e2 @ (corner - xa)])
        else:
            s, t = st_fixed
        point = xa + s * e1 + t * e2
        gap = (corner - point) @ normal + (sag_of(s, t) if sag_of else 0.0)
        kappa = float(p.constants["gamma"].value * p.constants["E"].value) * self.arc
        active = gap < 0 if state is None else state[0]
        f_n = kappa * max(-gap, 0.0) if state is None else kappa * (-gap) * active
        force = f_n * normal
        zero = np.zeros(3)
        if not (self.friction and active):
            return force, (s, t), gap, (active, True, zero), zero
        xa0, xb0, xc0 = self._old_segment
        slip = (corner - self.corner_old[k]) - (point - (xa0 + s * (xb0 - xa0) + t * (xc0 - xa0)))
        slip = slip - (slip @ normal) * normal
        old = self.tangential_old[k] - (self.tangential_old[k] @ normal) * normal
        kappa_t = float(p.constants["gamma_t"].value * p.constants["E"].value) * self.arc
        trial = old - kappa_t * slip
        bound = float(p.constants["mu"].value) * f_n
        size = np.linalg.norm(trial)
        stick = size <= bound if state is None else state[1]
        direction = trial / size if size > 0 else zero
        f_t = trial if stick else bound * (direction if state is None else state[2])
        return force + f_t, (s, t), gap, (active, stick, direction), f_t

    def _find(self, corner, u):
        """Best facet on this rank: (distance, row) with the point projecting inside it."""
        if not len(self.segments):
            return np.inf, -1
        x = self.coordinates + u.reshape(-1, 3)
        xa, xb, xc = (x[self.segments[:, j]] for j in range(3))
        e1, e2, w = xb - xa, xc - xa, corner - xa
        d11, d12, d22 = (np.einsum("ij,ij->i", a, b) for a, b in ((e1, e1), (e1, e2), (e2, e2)))
        w1, w2 = np.einsum("ij,ij->i", w, e1), np.einsum("ij,ij->i", w, e2)
        det = d11 * d22 - d12 * d12
        s, t = (d22 * w1 - d12 * w2) / det, (d11 * w2 - d12 * w1) / det
        normal = np.cross(e1, e2)
        distance = np.abs(np.einsum("ij,ij->i", w, normal)) / np.linalg.norm(normal, axis=1)
        tol = 1e-9
        distance[(s < -tol) | (t < -tol) | (s + t > 1 + tol) | (distance > self.search)] = np.inf
        row = int(np.argmin(distance))
        return (float(distance[row]), row) if np.isfinite(distance[row]) else (np.inf, -1)

    def contributions(self, with_jacobian: bool):
        """Per active rim point on this rank: (dofs (9,), C entries (9,), dC/du (9x9), dC/dr (9 x 6))."""
        p = self.problem
        self.coordinates = p.V.tabulate_dof_coordinates()[:, :3]
        u = p.u.x.array
        comm = p.mesh.comm
        places = np.array([p.rigid.place(point + _tip(p)) for point in self.points]).reshape(-1, 3)
        found = [self._find(corner, u) for corner in places]
        owners = np.argmin(np.array(comm.allgather([d for d, _ in found])).reshape(comm.size, -1), axis=0)
        out = []
        self.active[:] = False
        for k, point in enumerate(self.points):
            row = found[k][1]
            if comm.rank != owners[k] or row < 0:
                continue
            nodes = self.segments[row]
            self._old_segment = tuple(self._x(i, self.u_old) for i in nodes[:3])
            sag_of = lambda s, t, row=row: self._sag(row, s, t)  # noqa: E731
            force, st, gap, state, f_t = self._force(k, places[k], *(self._x(i, u) for i in nodes), sag_of=sag_of)
            if not state[0]:
                continue
            self.active[k] = True
            self.tangential[k] = f_t
            dofs = np.array([3 * i + j for i in nodes[:3] for j in range(3)], dtype=np.int32)
            weights = np.array([1 - st[0] - st[1], st[0], st[1]])
            entries = np.kron(weights, force)
            dC_du = dC_dr = None
            if with_jacobian:
                dC_du, dC_dr = self._derivatives(k, point, nodes, state, sag_of)
            out.append((dofs, entries, dC_du, dC_dr))
        active = comm.allreduce(int(self.active.sum()), op=MPI.SUM)
        return out, active

    def _derivatives(self, k, point, nodes, state, sag_of, h=1e-9):
        """Central differences of the C entries in the 9 facet dofs and the rigid dofs."""
        p = self.problem
        u = p.u.x.array
        x = [self._x(i, u) for i in nodes]
        r0 = p.rigid.values.copy()

        def entries(dx, r):
            corner = p.rigid.place(point + _tip(p), r)
            moved = [x[j] + dx[3 * j: 3 * j + 3] for j in range(3)]
            force, st, *_ = self._force(k, corner, *moved, x[3], sag_of=sag_of, state=state)
            return np.kron([1 - st[0] - st[1], st[0], st[1]], force)

        dC_du = np.zeros((9, 9))
        for j in range(9):
            e = np.zeros(9)
            e[j] = h
            dC_du[:, j] = (entries(e, r0) - entries(-e, r0)) / (2 * h)
        dC_dr = np.zeros((9, len(r0)))
        zero = np.zeros(9)
        for j in range(len(r0)):
            e = np.zeros(len(r0))
            e[j] = h
            dC_dr[:, j] = (entries(zero, r0 + e) - entries(zero, r0 - e)) / (2 * h)
        return dC_du, dC_dr

    def commit(self) -> None:
        p = self.problem
        self.tangential_old[:] = np.where(self.active[:, None], self.tangential, 0.0)
        self.corner_old = np.array([p.rigid.place(pt + _tip(p)) for pt in self.points]).reshape(-1, 3)
        self.u_old = p.u.x.array.copy()


def _tip(problem) -> np.ndarray:
    """Offset from the reference-point frame to the tip-centred frame used by RigidBody.place."""
    from femcontact.obstacle import reference_point

    return reference_point(problem.model.rigid)
