"""Frictionless normal contact with the rigid body (always built).

Nitsche's method (default): pressure p = [p_sigma - gamma_N g]_+ with gamma_N = gamma E / h,
or penalty p = [-gamma_N g]_+, against the rigid body's analytic signed distance g in
its own frame. Provides `problem.contact` (xi, gap, normal, normal_local, pressure) for
friction and outputs, and the normal traction p n.

With `contact.surface = "exact"` the contact points of the facets that mesh a surface of
revolution (a round hole's wall and chamfer) are moved radially onto that surface before the
gap is measured (`exact_surface_point`): the flat facets' chords, which lie
inside the hole by up to h^2/(8R), no longer touch the peg, and the contact can be integrated
at more points than the facets' vertices.

With `contact.normal = "wall"` the force acts along the wall's normal (`wall_normal`) wherever
the wall is smooth (`smooth_wall`): a rigid edge or a rounded rim pressing a smooth wall pushes
along the wall's normal, while the wall's nodes that sample it see the body's flank or rounding,
whose normal leans by their position on it. At the wall's edges the force acts along the body's
normal turned into the edge's normal cone (`edge_normals`, `into_arc`), the directions between
the normals of the two faces that meet there: a rounded rim rolling over the edge pushes along
its own normal, but a node on the edge that samples a rim still on one face, a fraction of a
millimetre away, sees the rim's normal turned past that face's and takes the face's. Where a wall
sinks round the body's edge onto its next face (the two normals more than WALL_BODY_ANGLE
apart), the body's normal is kept.

The rules below put the contact points on the facets' nodes (`Problem.contact_measure`).
"""
from types import SimpleNamespace

import numpy as np
import ufl
from dolfinx import cpp, fem
from dolfinx.fem import petsc
from petsc4py import PETSc

from femcontact.effects.base import Effect
from femcontact.jit import compile_forms
from femcontact.physics.signed_distance import signed_distance


def exact_surface_point(problem):
    """The reference position x (mm, UFL) of the contact points, moved radially onto the exact
    surface of revolution (`Model.revolution`): x + w (r_h / r - 1) x_r, with x_r the part of
    x - point across the axis, r = |x_r|, r_h the mesh nodes' r interpolated linearly (so the
    exact radius of a cylinder, and of a cone at the point's height) and w 1 at the nodes of
    those facets, 0 at all others (a flat facet beside them keeps its points to within h^2 / 8R)."""
    model, x = problem.model, ufl.SpatialCoordinate(problem.mesh)
    point, direction = np.asarray(model.revolution["point"]), np.asarray(model.revolution["direction"])
    Q = fem.FunctionSpace(problem.mesh, ("CG", 1))

    def radius(X):
        d = X[: problem.dim].T - point
        return np.linalg.norm(d - np.outer(d @ direction, direction), axis=1)

    r_h, w = fem.Function(Q), fem.Function(Q)
    r_h.interpolate(radius)
    fdim = problem.mesh.topology.dim - 1
    for name in model.revolution["facets"]:  # with the nodes other ranks' facets hold (remote dofs)
        w.x.array[fem.locate_dofs_topological(Q, fdim, model.facet_tags.find(model.facets[name]))] = 1.0
    p0, a = ufl.as_vector(point.tolist()), ufl.as_vector(direction.tolist())
    radial = (x - p0) - ufl.dot(x - p0, a) * a
    r = ufl.sqrt(ufl.dot(radial, radial))  # > 0: the hole block has no point on its axis
    return x + w * (r_h / r - 1) * radial


VERTEX_RULE = {"quadrature_points": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], "quadrature_weights": [1 / 6] * 3}
"""Contact points on a reference triangle (area 1/2) for 3-D P1 facets: its vertices."""
EXACT_SURFACE_RULE = {"quadrature_points": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
                      "quadrature_weights": [1 / 24] * 3 + [1 / 8] * 3}
"""Contact points on a reference triangle (area 1/2) for exact surfaces: the vertex rule on the four
triangles that halve its edges (`VERTEX_RULE` on each), so the points are the nodes of a
quadratic triangle."""
P2_NODE_RULE = {"quadrature_points": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5],
                                      [1 / 3, 1 / 3]],
                "quadrature_weights": [1 / 40] * 3 + [1 / 15] * 3 + [9 / 40]}
"""Contact points on a reference triangle (area 1/2) for 3-D P2 facets: its six nodes and its
centroid, positive weights, exact for cubics. A sharp edge of the contact surface lies on nodes,
so its contact is seen where Gauss points inside the facets would let it penetrate."""

SMOOTH_WALL_ANGLE = np.radians(20.0)
"""A boundary node whose facets' normals all lie within this angle of their mean is on a smooth
part of the wall (a cylinder's facets meet at h/R, a chamfer's edge at 45 deg, a mouth at 90)."""
SMOOTH_POINT = 0.5
"""A contact point takes the wall's normal where `smooth_wall` exceeds this: at the smooth nodes
of the wall's facets and inside its faces (a facet's centroid beside an edge: at least 7/9), not
on an edge."""
WALL_BODY_ANGLE = np.radians(45.0)
"""A contact point takes the wall's normal only where it lies within this angle of the body's: a
rim pressing the wall (the body's normal off by its tilt or rounding) does; a wall wrapped round
the body's edge, touching its next face, does not."""


def wall_normal(problem, exact: bool):
    """The deformable body's outward unit normal at the contact points, turned by its
    deformation (Nanson: F^-T N). On an exact surface of revolution (`exact_surface_point`) the
    flat facet's normal keeps its slope along the axis and points across it radially, as the
    cylinder's or cone's own does."""
    return deformed_normal(problem, ufl.FacetNormal(problem.mesh), exact)


def deformed_normal(problem, N, exact: bool):
    """The reference unit normal N (UFL) of the deformable body turned by its deformation
    (Nanson: F^-T N), made radial on an exact surface of revolution as in `wall_normal`."""
    mesh, dim = problem.mesh, problem.dim
    if exact:
        revolution = problem.model.revolution
        a = ufl.as_vector(list(revolution["direction"]))
        d = ufl.SpatialCoordinate(mesh) - ufl.as_vector(list(revolution["point"]))
        radial = d - ufl.dot(d, a) * a
        e_r = radial / ufl.sqrt(ufl.dot(radial, radial))
        along = ufl.dot(N, a)
        across = ufl.sqrt(ufl.max_value(1 - along ** 2, 0.0)) * ufl.sign(ufl.dot(N, e_r))
        N = along * a + across * e_r
    n = ufl.inv(ufl.Identity(dim) + ufl.grad(problem.u)).T * N
    return n / ufl.sqrt(ufl.dot(n, n))


def into_arc(n, a, b):
    """The unit vector n (UFL) turned into the arc of directions from the unit vector a to b (less
    than 180 deg apart): n itself where it lies between them, else the nearer end. Where a and b
    nearly coincide (less than 0.5 deg apart), a."""
    across = b - ufl.dot(b, a) * a  # towards b, square to a
    back = a - ufl.dot(a, b) * b  # towards a, square to b
    width2 = ufl.dot(across, across)
    inside = ufl.conditional(ufl.lt(ufl.dot(n, across), 0), a, ufl.conditional(ufl.lt(ufl.dot(n, back), 0), b, n))
    return ufl.conditional(ufl.lt(width2, np.sin(np.radians(0.5)) ** 2), a, inside)


def edge_normals(mean) -> tuple:
    """The two ends of the deformable body's normal cone at the nodes of its boundary facets, as
    quadratic vector functions (unit, reference configuration; quadratic so that an edge
    midpoint inside a face gets that face's normal, not its end nodes' mix): at a point on an
    edge the mean normals of the facets on either side of it, at a point inside a face its
    normal twice. The facets at a point are split by their normal's component along
    EDGE_SIDE_ORDER, above or below their mean's (`mean`, from `mean_normal`), so the face nearer
    the hole's axis comes first at every point of an edge. Sums over facets, so every rank gets
    the same values at a shared point."""
    mesh = mean.function_space.mesh
    dim = mesh.geometry.dim
    ds, N = _nodal_measure(mesh), ufl.FacetNormal(mesh)
    q = ufl.TestFunction(mean.function_space)
    order = ufl.as_vector(EDGE_SIDE_ORDER[dim])
    upper = ufl.conditional(ufl.ge(ufl.dot(N - mean, order), 0), 1.0, 0.0)
    out = []
    for form in compile_forms([upper * ufl.dot(N, q) * ds, (1 - upper) * ufl.dot(N, q) * ds]):
        side = _assembled(form).reshape(-1, dim)
        empty = np.linalg.norm(side, axis=1) < 1e-300  # every facet on the other side: a smooth point
        side[empty] = mean.x.array.reshape(-1, dim)[empty]
        out.append(fem.Function(mean.function_space))
        out[-1].x.array[:] = _unit_rows(side.reshape(-1), dim)
    return tuple(out)


NODE_RULES = {2: {"quadrature_rule": "custom", "quadrature_degree": 2, "quadrature_points": [[0.0], [1.0], [0.5]],
                  "quadrature_weights": [1 / 6, 1 / 6, 2 / 3]},
              3: {"quadrature_rule": "custom", "quadrature_degree": 2, **EXACT_SURFACE_RULE}}
"""Boundary points at the nodes of a quadratic facet (its vertices and edge midpoints), positive
weights, for sums over the facets at each node."""
EDGE_SIDE_ORDER = {2: (0.3, 0.954), 3: (0.1, 0.3, 0.949)}
"""A direction near the hole's axis (y in 2-D, z in 3-D) that tells the two faces at an edge
apart: their normals' components along it differ at every edge of the built geometries (an edge
whose faces' normals had equal components would not be split, and take its mean normal)."""


def _nodal_measure(mesh):
    """The boundary measure with its points at the nodes of quadratic facets (NODE_RULES)."""
    return ufl.Measure("ds", domain=mesh, metadata=NODE_RULES[mesh.geometry.dim])


def _unit_rows(values: np.ndarray, dim: int) -> np.ndarray:
    """A flat array of dim-vectors, each scaled to unit length (a zero one left zero)."""
    rows = values.reshape(-1, dim)
    return (rows / np.maximum(np.linalg.norm(rows, axis=1), 1e-300)[:, None]).reshape(-1)


def smooth_wall(mean):
    """1 at the nodes of the boundary facets where the deformable body's surface is smooth, 0 on
    its edges and corners (a point where some boundary facet's normal lies more than
    SMOOTH_WALL_ANGLE from the facets' mean normal `mean` there, from `mean_normal`), as a
    quadratic function: at a facet's vertices and edge midpoints the value of that point, so a
    midpoint inside a face is smooth beside an edge."""
    mesh = mean.function_space.mesh
    smooth = fem.Function(fem.FunctionSpace(mesh, ("CG", 2)), name="smooth_wall")
    apart = ufl.conditional(ufl.lt(ufl.dot(ufl.FacetNormal(mesh), mean), np.cos(SMOOTH_WALL_ANGLE)), 1.0, 0.0)
    apart_form, = compile_forms([apart * ufl.TestFunction(smooth.function_space) * _nodal_measure(mesh)])
    smooth.x.array[:] = np.where(_assembled(apart_form) > 0, 0.0, 1.0)
    return smooth


def mean_normal(mesh):
    """The unit mean of the boundary facets' outward normals at the nodes of the boundary facets
    (vertices and edge midpoints), as a quadratic vector function (0 inside)."""
    mean = fem.Function(fem.VectorFunctionSpace(mesh, ("CG", 2)))
    form, = compile_forms([ufl.dot(ufl.FacetNormal(mesh), ufl.TestFunction(mean.function_space)) * _nodal_measure(mesh)])
    mean.x.array[:] = _unit_rows(_assembled(form), mesh.geometry.dim)
    return mean


def summed_vector(form) -> PETSc.Vec:
    """The PETSc vector of a compiled linear form, summed over the ranks, its ghosts too."""
    vector = petsc.assemble_vector(form)
    vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    return vector


def _assembled(form) -> np.ndarray:
    """`summed_vector`'s values at the local and ghost dofs."""
    vector = summed_vector(form)
    with vector.localForm() as local:
        values = local.array.copy()
    vector.destroy()
    return values


class NormalContact(Effect):
    name = "contact"

    def constants(self, scene: dict, body: str) -> dict:
        contact = scene["contact"]
        return {"gamma": contact["gamma"], "theta": contact["theta"]}

    def build(self, problem) -> None:
        c, rigid, scene = problem.constants, problem.rigid, problem.scene
        exact = scene["contact"]["surface"] == "exact"
        x = (exact_surface_point(problem) if exact else ufl.SpatialCoordinate(problem.mesh)) + problem.u
        xi = ufl.variable(rigid.to_local(x, rigid.variable))
        gap = signed_distance(problem.shape, xi)
        normal_local = ufl.diff(gap, xi)
        normal = rigid.to_global_direction(normal_local, rigid.variable)
        if scene["contact"]["normal"] == "wall":  # the wall pushes along its own normal where smooth
            wall, mean = -wall_normal(problem, exact), mean_normal(problem.mesh)
            along_wall = ufl.And(ufl.gt(smooth_wall(mean), SMOOTH_POINT),
                                 ufl.gt(ufl.dot(wall, normal), np.cos(WALL_BODY_ANGLE)))
            side_a, side_b = (-deformed_normal(problem, n, exact) for n in edge_normals(mean))
            at_edge = into_arc(normal, side_a, side_b)
            at_edge = ufl.conditional(ufl.gt(ufl.dot(at_edge, normal), np.cos(WALL_BODY_ANGLE)), at_edge, normal)
            normal = ufl.conditional(along_wall, wall, at_edge)
            normal_local = rigid.to_local_direction(normal, rigid.variable)
        p_sigma = ufl.dot(problem.stress * ufl.FacetNormal(problem.mesh), normal)
        gamma_n = c["gamma"] * c["E"] / cell_diameter(problem.mesh)
        trial = p_sigma - gamma_n * gap if scene["contact"]["method"] == "nitsche" else -gamma_n * gap
        # [trial]_+ with the kink counted as active, so a body touching with zero force
        # already gets the contact stiffness in Newton's first iteration
        pressure = ufl.conditional(ufl.ge(trial, 0), trial, 0.0)
        problem.contact = SimpleNamespace(xi=xi, gap=gap, normal=normal, normal_local=normal_local,
                                          pressure=pressure)
        problem.add_traction(pressure * normal)
        if scene["contact"]["theta"] != 0:
            # Nitsche's theta-term: -(theta/gamma_N) (p_sigma(u) - p) p_sigma(v)
            dstress = ufl.derivative(problem.stress, problem.u, problem.v)
            p_sigma_v = ufl.dot(dstress * ufl.FacetNormal(problem.mesh), normal)
            problem.add_contact_term(-c["theta"] / gamma_n * (p_sigma - pressure) * p_sigma_v)

    def contact_stiffness(self) -> float:
        """gamma_N = gamma E / h_contact (N/mm^3), the penalty part of the pressure per mm of gap."""
        c = self.problem.constants
        return float(c["gamma"].value * c["E"].value) / self.problem.contact_size


def cell_diameter(mesh):
    """Each cell's diameter (mm), the largest distance between two of its vertices, as a DG0
    function: ufl.CellDiameter's value, also on curved (quadratic) cells, which FFCx cannot
    compute it for."""
    space = fem.FunctionSpace(mesh, ("DG", 0))
    tdim = mesh.topology.dim
    cells = np.arange(mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts,
                      dtype=np.int32)
    h = fem.Function(space, name="cell_diameter")
    h.x.array[space.dofmap.list.array] = cpp.mesh.h(mesh._mesh, tdim, cells)  # 0.5.2: h takes the C++ mesh
    return h
