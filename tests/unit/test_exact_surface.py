"""The contact on exact surfaces (`contact.surface = "exact"`, effects/contact.py): the contact
points of a round hole's wall and chamfer lie on the exact cylinder or cone, where the flat
facets' edge midpoints lie inside it by up to h^2 / (8R).

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

from femcontact.effects.contact import exact_surface_point
from femcontact.families import load_scene
from femcontact.problem.problem import EXACT_SURFACE_RULE, P2_NODE_RULE
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
