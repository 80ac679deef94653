"""Sharp corners of a rigid body against the deformable surface (2-D, P1).

The contact integral sees the rigid body only through its signed distance, which is
right where a corner of the deformable body presses a rigid face, but blind where a
sharp rigid corner presses a deformable face: at the micrometre penetrations of these
loads no mesh node lies inside the corner. Each sharp corner of the rigid body is
therefore also a slave point of a node-to-segment element against the deformable
contact surface (the two-pass idea of engineering codes): penalty normal force
f_n = kappa [-g]_+ with kappa = gamma * E (N/mm per mm of thickness, the stiffness a
contact node gets from the Nitsche term), and, with friction, the Coulomb return map
(`physics.coulomb`) on the tangential force with the slip measured relative to the surface's material
point. The force enters the contact vector C at the segment's two nodes, so the
rigid-body rows of the Newton system follow from C as for the integral terms. The
element's Jacobian is taken by central differences with the contact state frozen.

In 3-D the rims of a rigid cylinder are not treated this way: node-to-triangle rim points
do not converge (docs/wedging_3d.md); the rim is seen once the wall nodes next to it touch
the peg's side.
"""
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from femcontact.effects.base import Effect
from femcontact.physics.coulomb import coulomb_projection, sticks
from femcontact.physics.rotation import rotation_numpy

SMOOTH_ANGLE = np.radians(30.0)
"""Two facets meeting at a node at less than this angle (reference configuration) share the
node's normal: mesh facets of one smooth face do, the faces of a geometric corner do not."""

TOUCHING = 1e3 * np.finfo(float).eps
"""Gap (relative to the body's size) within which a corner counts as touching: a corner placed
on the surface lands there to round-off (3.6e-15 mm in the default 2-D wedging case). As the
Nitsche term counts its kink as active, a touching corner already gets the contact stiffness
in Newton's first iteration, so the body cannot turn into the surface unopposed."""


def corner_points(rigid: dict) -> np.ndarray:
    """Sharp corners of a 2-D rectangle in its shape frame about the reference point; with a
    tip chamfer, the chamfer's two ends on either side instead of the tip corners."""
    if rigid["shape"] != "rectangle" or rigid["corner_radius"] > 0:
        return np.zeros((0, 2))
    w, h, cw = rigid["half_width"], rigid["length"] / 2, rigid["chamfer_width"]
    if cw > 0:
        top_of_chamfer = cw / np.tan(np.radians(rigid["chamfer_angle"])) - h
        tip = [[-w, top_of_chamfer], [-w + cw, -h], [w - cw, -h], [w, top_of_chamfer]]
    else:
        tip = [[-w, -h], [w, -h]]
    return np.array([*tip, [w, h], [-w, h]])


class RigidCorners(Effect):
    """Node-to-segment contact of the rigid body's sharp corners (2-D, P1)."""
    name = "rigid_corners"

    @staticmethod
    def applies(problem) -> bool:
        """Built when the rigid shape has sharp corners, in 2-D with P1 elements."""
        return problem.dim == 2 and problem.scene["mesh"]["degree"] == 1 and len(corner_points(problem.model.rigid)) > 0

    def __init__(self, problem):
        super().__init__(problem)
        p = problem
        self.points = corner_points(p.model.rigid)
        self.friction = "friction" in p.effects
        self.segments = self._segments()
        self.coordinates = p.V.tabulate_dof_coordinates()[:, :2]
        start = sum(p.mesh.comm.allgather(len(self.segments))[:p.mesh.comm.rank])
        self.owned = slice(start, start + len(self.segments))  # this rank's rows of `_all_normals`
        self.neighbours = self._neighbours()
        self.active_count = 0
        self.search = 4 * p.model.h_contact
        self.touching = TOUCHING * p.extent  # mm
        n = len(self.points)
        self.tangential_old = np.zeros(n)
        self.tangential = np.zeros(n)
        self.corner_old = self._placed()
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

    def _normals(self, u: np.ndarray) -> np.ndarray:
        """Outward unit normals of this rank's segments for the displacement `u` (m x 2)."""
        u = u.reshape(-1, 2)
        a, b, c = (self.segments[:, i] for i in range(3))
        xa, xb, xc = (self.coordinates[i] + u[i] for i in (a, b, c))
        return _outward(xb - xa, xa - xc)

    def _all_normals(self, u: np.ndarray) -> np.ndarray:
        """The normals of every rank's segments, in rank order (collective)."""
        comm = self.problem.mesh.comm
        normals = self._normals(u)
        return np.concatenate(comm.allgather(normals)) if comm.size > 1 else normals

    def _neighbours(self) -> np.ndarray:
        """For each end (a, b) of this rank's segments, the index (in `_all_normals`) of the
        segment that shares its node and whose normal it is averaged with, or -1 (collective)."""
        comm = self.problem.mesh.comm
        imap = self.problem.V.dofmap.index_map
        ends = imap.local_to_global(self.segments[:, :2].reshape(-1).astype(np.int32)).reshape(-1, 2)
        all_ends = np.concatenate(comm.allgather(ends)).reshape(-1, 2)
        normals = self._all_normals(np.zeros_like(self.problem.u.x.array))
        offset = self.owned.start
        out = np.full(ends.shape, -1, dtype=np.int64)
        for i, pair in enumerate(ends):
            for j, node in enumerate(pair):
                other = [m for m in np.flatnonzero((all_ends == node).any(axis=1)) if m != offset + i]
                if len(other) == 1 and normals[offset + i] @ normals[other[0]] > np.cos(SMOOTH_ANGLE):
                    out[i, j] = other[0]
        return out

    def _placed(self, values=None) -> np.ndarray:
        """Current positions of all corners (mm) for the pose `values` (default: the current one)."""
        rigid = self.problem.rigid
        t, angles = rigid.split(rigid.values if values is None else values)
        return rigid.p0 + np.asarray(t) + self.points @ (rotation_numpy(angles) @ rigid.Q0).T

    # -- the element ------------------------------------------------------------------
    def _force(self, k: int, corner: np.ndarray, xa, xb, xc, neighbour_normals, state=None):
        """Force on the rigid corner (N), the segment parameter, the gap (mm), the contact state,
        the tangential force (N) and the normal for one corner against one segment;
        `neighbour_normals` (2 x 2, NaN where none) are the normals averaged in at its nodes."""
        p = self.problem
        edge = xb - xa
        ends = _end_normals(_outward(edge[None], (xa - xc)[None])[0], neighbour_normals)
        s = float(np.clip(_projection(corner - xa, edge, ends[0], ends[1]), 0.0, 1.0))
        normal = ends[0] + s * (ends[1] - ends[0])
        normal /= np.linalg.norm(normal)
        point = xa + s * edge
        gap = (corner - point) @ normal
        kappa = float(p.constants["gamma"].value * p.constants["E"].value)
        active = gap <= self.touching if state is None else state[0]
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
            if state is None:
                stick, f_t = sticks(trial, bound), coulomb_projection(trial, bound)
            else:  # the derivatives: stick or slip (in the direction it slipped) frozen
                stick = state[1]
                f_t = trial if stick else state[2] * bound
            force = force + f_t * tangent
            return force, s, gap, (active, stick, np.sign(trial)), f_t, normal
        return force, s, gap, (active, True, 0.0), f_t, normal

    def _find(self, corners: np.ndarray, u: np.ndarray, all_normals: np.ndarray):
        """Best segment on this rank for each corner: (distances, rows), the corner projecting
        inside the segment along the smoothed normal and within the search distance (else inf, -1)."""
        n = len(corners)
        if not len(self.segments):
            return np.full(n, np.inf), np.full(n, -1)
        u = u.reshape(-1, 2)
        a, b = self.segments[:, 0], self.segments[:, 1]
        xa, xb = self.coordinates[a] + u[a], self.coordinates[b] + u[b]
        edge = xb - xa
        ends = _end_normals(all_normals[self.owned], self._neighbour_normals(slice(None), all_normals))
        arm = corners[:, None, :] - xa[None, :, :]  # corners x segments x 2
        t = _projection(arm, edge, ends[:, 0], ends[:, 1])
        normal = ends[None, :, 0] + t[:, :, None] * (ends[None, :, 1] - ends[None, :, 0])
        offset = arm - t[:, :, None] * edge[None]
        distance = np.abs(np.einsum("csj,csj->cs", offset, normal)) / np.linalg.norm(normal, axis=2)
        distance[~((t >= -1e-9) & (t <= 1 + 1e-9)) | (distance > self.search)] = np.inf
        rows = np.argmin(distance, axis=1)
        best = distance[np.arange(n), rows]
        return best, np.where(np.isfinite(best), rows, -1)

    def _pressing(self):
        """Each touching corner this rank owns: (k, (a, b, c) segment nodes, force on the corner,
        s, gap, state, f_t), from `_force`."""
        p = self.problem
        u = p.u.x.array
        comm = p.mesh.comm
        corners = self._placed()
        all_normals = self._all_normals(u)
        distances, rows = self._find(corners, u, all_normals)
        owners = np.zeros(len(rows), dtype=int)
        if comm.size > 1:
            owners = np.argmin(np.array(comm.allgather(distances)).reshape(comm.size, -1), axis=0)
        for k, row in enumerate(rows):
            if comm.rank != owners[k] or row < 0:
                continue
            a, b, c = self.segments[row]
            self._old_segment = (self.coordinates[a] + self.u_old[2 * a: 2 * a + 2],
                                 self.coordinates[b] + self.u_old[2 * b: 2 * b + 2])
            xa, xb, xc = (self.coordinates[i] + u[2 * i: 2 * i + 2] for i in (a, b, c))
            neighbour_normals = self._neighbour_normals(row, all_normals)
            force, s, gap, state, f_t, normal = self._force(k, corners[k], xa, xb, xc, neighbour_normals)
            if state[0]:
                yield k, (a, b, c), neighbour_normals, force, s, gap, state, f_t, normal

    def _neighbour_normals(self, rows, all_normals: np.ndarray) -> np.ndarray:
        """The normals averaged in at the two nodes of segments `rows` (an index or a slice):
        (..., 2, 2), NaN where none."""
        neighbours = self.neighbours[rows]
        return np.where((neighbours >= 0)[..., None], all_normals[neighbours], np.nan)

    def contributions(self, with_jacobian: bool):
        """Per active corner on this rank: (dofs (4,), C entries (4,), dC/du (4x4), dC/dr (4 x n_r))."""
        out = []
        self.active[:] = False
        for k, (a, b, c), neighbour_normals, force, s, gap, state, f_t, _ in self._pressing():
            self.active[k] = gap < 0  # pressing (a touching corner adds only its stiffness)
            self.tangential[k] = f_t
            dofs = np.array([2 * a, 2 * a + 1, 2 * b, 2 * b + 1], dtype=np.int32)
            entries = np.r_[(1 - s) * force, s * force]
            dC_du = dC_dr = None
            if with_jacobian:
                dC_du, dC_dr = self._derivatives(k, (a, b, c), neighbour_normals, state)
            out.append((dofs, entries, dC_du, dC_dr))
        active = self.problem.mesh.comm.allreduce(int(self.active.sum()), op=MPI.SUM)
        return out, active

    def point_contacts(self) -> list:
        """The pressing corners' forces on the deformable body (the hook's tuple); collective."""
        out = []
        for _, (a, b, _), _, force, s, gap, state, _, normal in self._pressing():
            if gap < 0:
                on_body = -force  # the corner pushes the body as the body pushes it back
                f_n = abs(on_body @ normal)
                out.append((a, b, s, f_n, on_body - (on_body @ normal) * normal, bool(state[1])))
        return out

    def _derivatives(self, k, nodes, neighbour_normals, state, h=1e-9):
        """Central differences of the C entries in the 4 segment dofs and the rigid dofs (the
        neighbouring facets' normals held)."""
        p = self.problem
        a, b, c = nodes
        base_u = p.u.x.array
        x = {i: self.coordinates[i] + base_u[2 * i: 2 * i + 2] for i in nodes}
        r0 = p.rigid.values.copy()

        def entries(dx_a, dx_b, r):
            corner = self._placed(r)[k]
            force, s, *_ = self._force(k, corner, x[a] + dx_a, x[b] + dx_b, x[c], neighbour_normals, state=state)
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
    def add_contact_residual(self, vector: PETSc.Vec) -> None:
        """Add the corners' C entries to the contact vector's local form (before ghost update)."""
        contributions, self.active_count = self.contributions(with_jacobian=False)
        with vector.localForm() as local:
            for dofs, entries, _, _ in contributions:
                local.array[dofs] += entries

    def add_contact_jacobian(self, matrices, kur, bc_dofs: set) -> None:
        """Add dC/du to each matrix (local indices) and dC/dr to the kur vectors' local forms
        (`kur`: rigid dof -> vector, the free dofs)."""
        contributions, _ = self.contributions(with_jacobian=True)
        for matrix in matrices:
            matrix.assemblyBegin(PETSc.Mat.AssemblyType.FLUSH)
            matrix.assemblyEnd(PETSc.Mat.AssemblyType.FLUSH)
        for dofs, _, dC_du, dC_dr in contributions:
            keep = np.array([d not in bc_dofs for d in dofs])
            rows = dofs[keep]
            for matrix in matrices:
                matrix.setValuesLocal(rows, rows, dC_du[np.ix_(keep, keep)], addv=PETSc.InsertMode.ADD_VALUES)
            for j, vector in kur.items():
                with vector.localForm() as local:
                    local.array[dofs] += dC_dr[:, j]

    def commit(self, dt: float) -> None:
        p = self.problem
        self.tangential_old[:] = np.where(self.active, self.tangential, 0.0)
        self.corner_old = self._placed()
        self.u_old = p.u.x.array.copy()

    def commit_contacts(self) -> None:
        """The corners' slip history moved to the current state (`commit`: it holds no time)."""
        self.commit(0.0)

    def state(self) -> dict:
        return {"tangential_old": self.tangential_old.copy(), "corner_old": self.corner_old.copy(),
                "u_old": self.u_old.copy()}

    def restore(self, state: dict) -> None:
        self.tangential_old[:] = state["tangential_old"]
        self.corner_old, self.u_old = state["corner_old"].copy(), state["u_old"].copy()

    def outputs(self) -> dict:
        return {"corner_contacts": self.active_count}


def _outward(edge: np.ndarray, away: np.ndarray) -> np.ndarray:
    """Unit normals of segments `edge` (m x 2) on the side of `away` (m x 2, a vector from a point
    inside the body to the segment)."""
    normal = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / np.linalg.norm(edge, axis=1)[:, None]
    return np.where((np.einsum("ij,ij->i", normal, away) < 0)[:, None], -normal, normal)


def _end_normals(own: np.ndarray, neighbour_normals: np.ndarray) -> np.ndarray:
    """Unit normals at the two nodes of segments whose own normals are `own` (..., 2): each the
    mean with the neighbouring facet's normal where `neighbour_normals` (..., 2, 2) has one."""
    ends = own[..., None, :] + np.nan_to_num(neighbour_normals)
    return ends / np.linalg.norm(ends, axis=-1)[..., None]


def _projection(arm, edge, normal_a, normal_b):
    """Parameter s of the point xa + s edge whose interpolated normal (1 - s) normal_a + s normal_b
    passes through the point xa + arm: the root near the straight projection of the quadratic
    cross(arm - s edge, normal_a + s (normal_b - normal_a)) = 0 (NaN where there is none).
    Broadcasts over leading axes."""
    def cross(v, w):
        return v[..., 0] * w[..., 1] - v[..., 1] * w[..., 0]
    turn = normal_b - normal_a
    quadratic = -cross(edge, turn)
    linear = cross(arm, turn) - cross(edge, normal_a)
    constant = cross(arm, normal_a)
    root = np.sqrt(np.maximum(linear ** 2 - 4 * quadratic * constant, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -2 * constant / (linear + np.where(linear < 0, -root, root))
    return np.where(linear ** 2 >= 4 * quadratic * constant, s, np.nan)
