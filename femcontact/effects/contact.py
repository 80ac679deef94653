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
"""
from types import SimpleNamespace

import numpy as np
import ufl
from dolfinx import fem

from femcontact.effects.base import Effect
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
    from dolfinx import cpp

    space = fem.FunctionSpace(mesh, ("DG", 0))
    tdim = mesh.topology.dim
    cells = np.arange(mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts,
                      dtype=np.int32)
    h = fem.Function(space, name="cell_diameter")
    h.x.array[space.dofmap.list.array] = cpp.mesh.h(mesh._mesh, tdim, cells)  # 0.5.2: h takes the C++ mesh
    return h
