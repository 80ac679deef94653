"""The contact on exact surfaces (`contact.surface = "exact"`, effects/contact.py): the contact
points of a round hole's wall and chamfer lie on the exact cylinder or cone, where the flat
facets' edge midpoints lie inside it by up to h^2 / (8R); on curved quadratic elements
(`mesh.geometry_order = 2`) the facets themselves follow the surfaces.

Measured as the root mean square of r - r_exact over the facets with the contact rule (P1:
vertices and edge midpoints; P2: those and the centroids), on a coarse insertion mesh (elements
1.5 to 3 mm, hole radius 5.05 mm): 1e-15 mm (round-off) on the exact surface, 0.03-0.04 mm on the
facets."""
from pathlib import Path

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from femcontact.effects.contact import EXACT_SURFACE_RULE, P2_NODE_RULE, exact_surface_point
from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENES = Path(__file__).parents[2] / "scenes"
RULES = {1: {"quadrature_rule": "custom", "quadrature_degree": 1, **EXACT_SURFACE_RULE},
         2: {"quadrature_rule": "custom", "quadrature_degree": 3, **P2_NODE_RULE}}


def radial_error(problem, x, name: str) -> float:
    """sqrt(mean (r(x) - r_exact)^2) (mm) over the facets `name`, r about the revolution's axis;
    r_exact is the radius of the wall (the hole's half width) or, on the chamfer,
    the cone's at the point's height."""
    model = problem.model
    point, direction = (ufl.as_vector(model.revolution[k]) for k in ("point", "direction"))
    radial = (x - point) - ufl.dot(x - point, direction) * direction
    r = ufl.sqrt(ufl.dot(radial, radial))
    scene = problem.scene
    if name == "hole_wall":
        exact = scene["hole"]["width"] / 2
    else:  # the hole's mouth chamfer: D/2 at z = -h_c, growing by tan(angle) per mm upwards
        hole = scene["hole"]
        angle = np.radians(hole["chamfer_angle"])
        h_c = hole["chamfer_width"] / np.tan(angle)
        exact = hole["width"] / 2 + (x[2] + h_c) * np.tan(angle)
    rule = RULES[scene["mesh"]["degree"]]
    ds = ufl.Measure("ds", domain=problem.mesh, subdomain_data=model.facet_tags, metadata=rule)(model.facets[name])
    comm = problem.mesh.comm
    square = comm.allreduce(fem.assemble_scalar(fem.form((r - exact) ** 2 * ds)), op=MPI.SUM)
    area = comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ds)), op=MPI.SUM)
    return float(np.sqrt(square / area))


@pytest.mark.parametrize("degree", [1, 2])
def test_contact_points_lie_on_the_exact_surface(degree):
    overrides = ["contact.surface='exact'", "mesh.contact_size=1.5", "mesh.size_max=3", f"mesh.degree={degree}"]
    problem = Simulation(load_scene(SCENES / "insertion_3d.toml", overrides)).problem
    exact, facets = exact_surface_point(problem), ufl.SpatialCoordinate(problem.mesh)
    for name in ("hole_wall", "hole_chamfer"):
        assert radial_error(problem, exact, name) < 1e-10, name
        assert radial_error(problem, facets, name) > 1e-3, name  # the chords' midpoints sag inside


def test_curved_elements_follow_the_cylinder_and_the_cone():
    """P2 on curved (quadratic) elements: the contact points (nodes and centroids) of the wall
    and the chamfer, measured on their own facets, lie within 3e-5 and 7e-4 mm (RMS: 2.6e-5 and
    6.4e-4 measured; the centroids, O(h^3)) of the exact surfaces, against 0.046 and 0.034 mm on
    flat facets."""
    base = ["mesh.contact_size=1.5", "mesh.size_max=3", "mesh.degree=2"]
    errors = {}
    for order in (1, 2):
        problem = Simulation(load_scene(SCENES / "insertion_3d.toml", base + [f"mesh.geometry_order={order}"])).problem
        assert problem.mesh.geometry.cmap.degree == order
        x = ufl.SpatialCoordinate(problem.mesh)
        errors[order] = [radial_error(problem, x, name) for name in ("hole_wall", "hole_chamfer")]
    assert errors[2][0] < 3e-5 and errors[2][1] < 7e-4
    assert errors[1][0] > 0.03 and errors[1][1] > 0.03


@pytest.mark.parametrize("dim", [2, 3])
def test_the_cell_diameter_is_ufl_s_on_straight_cells(dim):
    """Nitsche's gamma_N = gamma E / h takes h from `cell_diameter` (a DG0 function, which curved
    cells can use): on straight cells it is ufl.CellDiameter to round-off."""
    from dolfinx import mesh as dmesh

    from femcontact.effects.contact import cell_diameter

    comm = MPI.COMM_WORLD
    domain = (dmesh.create_unit_square(comm, 5, 3) if dim == 2 else dmesh.create_unit_cube(comm, 3, 2, 4))
    difference = fem.form((cell_diameter(domain) - ufl.CellDiameter(domain)) ** 2 * ufl.dx(domain))
    size = fem.form(ufl.CellDiameter(domain) ** 2 * ufl.dx(domain))
    assert comm.allreduce(fem.assemble_scalar(difference), op=MPI.SUM) < 1e-28 * comm.allreduce(
        fem.assemble_scalar(size), op=MPI.SUM)
