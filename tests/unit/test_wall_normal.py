"""The contact force along the wall's normal (`contact.normal = "wall"`, effects/contact.py).

`smooth_wall` marks the boundary nodes where the deformable body's surface is smooth: a node
is on an edge when some boundary facet there turns more than SMOOTH_WALL_ANGLE (20 deg) from
the facets' mean normal. Checked on meshes whose edges are known: the corners of a square and
the edges of a cube (90 deg), and a square's bottom side bent at its middle by 16 deg (smooth:
each facet 8 deg from the mean) and by 50 deg (an edge: 25 deg).

A frictionless contact on a flat wall pushes along the wall's normal: with the force along the
wall's normal the rigid body's tangential reaction is zero to round-off wherever the contact
points sit under it; along the rigid body's normal each point's force tilts by its offset over
the body's radius, and the sum keeps what the points' asymmetry leaves. On a round hole's exact
surface (`contact.surface = "exact"`) the wall's normal is the cylinder's or cone's own.

At an edge of the wall the force takes the body's normal turned into the edge's normal cone, the
arc between the two faces' normals (`edge_normals`, `into_arc`).
"""
from pathlib import Path

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from femcontact.effects.contact import edge_normals, into_arc, mean_normal, smooth_wall, wall_normal
from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENES = Path(__file__).parents[2] / "scenes"


def edge_nodes(mesh) -> np.ndarray:
    """Coordinates of the owned nodes `smooth_wall` puts on an edge."""
    smooth = smooth_wall(mean_normal(mesh))
    owned = smooth.function_space.dofmap.index_map.size_local
    x = smooth.function_space.tabulate_dof_coordinates()[:owned]
    return x[smooth.x.array[:owned] == 0.0]


def test_an_edge_s_normal_cone_spans_its_two_faces():
    """At the nodes on the lower edge of the round hole's chamfer (r = 5.05 mm, z = -1 mm) the two
    ends of the normal cone are the chamfer's and the wall's outward normals (up the cone at
    45 deg into the hole, and radially in), to within the facets' turn about the axis (1 mm
    contact elements on R = 5.05 mm: up to h / 2R, 0.1 rad)."""
    scene = load_scene(SCENES / "insertion_3d.toml", ["mesh.contact_size=1.0", "mesh.contact_zone=3.0"])
    upper, lower = edge_normals(mean_normal(Simulation(scene, MPI.COMM_SELF).problem.mesh))
    x = upper.function_space.tabulate_dof_coordinates()
    r = np.hypot(x[:, 0], x[:, 1])
    on_edge = np.isclose(r, 5.05, atol=1e-6) & np.isclose(x[:, 2], -1.0, atol=1e-6)
    assert on_edge.sum() >= 10
    inward = -x[on_edge, :2] / r[on_edge, None]
    cone = np.column_stack([inward, np.ones(on_edge.sum())]) / np.sqrt(2)
    wall = np.column_stack([inward, np.zeros(on_edge.sum())])
    for side, face in ((upper, cone), (lower, wall)):
        cosines = np.sum(side.x.array.reshape(-1, 3)[on_edge] * face, axis=1)
        assert np.arccos(np.clip(cosines, -1, 1)).max() < 0.1


@pytest.mark.parametrize("tilt_deg, expected_deg", [(-10.0, 0.0), (20.0, 20.0), (60.0, 45.0), (100.0, 45.0)])
def test_a_normal_beyond_an_edge_s_faces_takes_the_nearer_face_s(tilt_deg, expected_deg):
    """The arc from a (the x axis) to b (45 deg towards y): a normal inside it is kept, one beyond
    either end takes that end."""
    a, b = ufl.as_vector([1.0, 0.0]), ufl.as_vector([np.sqrt(0.5), np.sqrt(0.5)])
    t = np.radians(tilt_deg)
    turned = into_arc(ufl.as_vector([np.cos(t), np.sin(t)]), a, b)
    assert np.degrees(np.arctan2(float(turned[1]), float(turned[0]))) == pytest.approx(expected_deg, abs=1e-12)


def test_a_square_has_edges_at_its_corners():
    square = dmesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    corners = edge_nodes(square)[:, :2]
    found = np.concatenate(MPI.COMM_WORLD.allgather(corners))
    assert sorted(map(tuple, np.round(found, 12))) == [(0, 0), (0, 1), (1, 0), (1, 1)]


def test_a_cube_has_edges_along_its_edges():
    cube = dmesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 2)
    found = np.concatenate(MPI.COMM_WORLD.allgather(edge_nodes(cube)))
    on_two_faces = (np.isclose(found, 0) | np.isclose(found, 1)).sum(axis=1) >= 2
    assert len(found) == 8 + 12 * 3 and on_two_faces.all()  # per edge its middle vertex and two midpoints


@pytest.mark.parametrize("bend_deg, smooth", [(16.0, True), (50.0, False)])
def test_a_bent_side_is_smooth_below_the_angle(bend_deg, smooth):
    square = dmesh.create_unit_square(MPI.COMM_SELF, 2, 2)
    x = square.geometry.x
    middle = np.isclose(x[:, 0], 0.5) & np.isclose(x[:, 1], 0.0)
    x[middle, 1] = -0.5 * np.tan(np.radians(bend_deg / 2))
    found = edge_nodes(square)[:, :2]
    at_bend = np.isclose(found[:, 0], 0.5) & (found[:, 1] < 0)
    assert at_bend.any() != smooth
    assert len(found) == 4 + (not smooth)


@pytest.mark.parametrize("normal", ["wall", "body"])
def test_a_frictionless_flat_wall_pushes_along_its_normal(normal):
    """The 2-D Hertz scene's cylinder pressed 5 um into the block, 0.07 mm (a third of a contact
    element) to the side of the nodes' symmetric layout."""
    scene = load_scene(SCENES / "hertz.toml", ["mesh.contact_size=0.2", f"contact.normal='{normal}'"])
    simulation = Simulation(scene)
    rigid = simulation.problem.rigid
    rigid.values[:] = [0.07, -0.005, 0.0]
    rigid.sync()
    load = simulation.schedule.load(0, 0.25, 0.25)
    _, R_r, _ = simulation.newton.assemble_residual(load)
    tangential, pressing = -(R_r + load.generalized_force(rigid.values))[:2]  # the contact's force on the body
    assert abs(pressing) > 10.0  # N/mm: the contact carries a force
    if normal == "wall":
        assert abs(tangential) <= 1e-12 * abs(pressing)
    else:
        assert abs(tangential) > 1e-6 * abs(pressing)  # 1.0e-5 of it


@pytest.mark.parametrize("surface", ["exact", "facets"])
def test_the_exact_wall_normal_has_no_circumferential_part(surface):
    """On the round hole's cylinder and cone the exact surface's normal lies in the plane of the
    axis (n . t = 0, t the circumferential direction), to round-off; a flat facet's normal turns
    by up to h / 2R about the axis (1 mm contact elements on R = 5.05 mm, 2 mm further off: RMS
    measured 3e-17 and 0.055)."""
    scene = load_scene(SCENES / "insertion_3d.toml", ["mesh.contact_size=1.0", "mesh.contact_zone=3.0",
                                                       f"contact.surface='{surface}'"])
    problem = Simulation(scene, MPI.COMM_SELF).problem
    model = problem.model
    n = wall_normal(problem, surface == "exact")
    x = ufl.SpatialCoordinate(problem.mesh)
    t = ufl.as_vector([-x[1], x[0], 0.0]) / ufl.sqrt(x[0] ** 2 + x[1] ** 2)  # the axis is z through 0
    ds = ufl.Measure("ds", domain=problem.mesh, subdomain_data=model.facet_tags, metadata={"quadrature_degree": 4})
    walls = ds(tuple(model.facets[name] for name in model.revolution["facets"]))
    area = fem.assemble_scalar(fem.form(1.0 * walls))
    rms = np.sqrt(fem.assemble_scalar(fem.form(ufl.dot(n, t) ** 2 * walls)) / area)
    if surface == "exact":
        assert rms < 1e-12
    else:
        assert 0.01 < rms < 0.1


def test_a_compliant_wall_wrapped_round_the_peg_s_corner_keeps_the_peg_s_normal_there():
    """Thesis case 2 wedged (l_d 8, Mz 1500 N*mm, the peg's inertia) in blocks 65 times more
    compliant (E = 2969 MPa), resolution 0.5: the peg's corner sinks into the wall, which wraps
    round it onto the tip face. Where the wall's normal lies more than WALL_BODY_ANGLE (45 deg)
    from the peg's, the contact takes the peg's: along the wall's normal everywhere, the wall's
    points under the tip face push sideways, and the load step stalls (measured: 8 cuts, then
    40 Newton iterations ending at a residual of 1.06 N). The wedge holds inside the friction
    cones (measured |Fy / Fx| = 0.096 at both contacts, mu = 0.2), balanced to round-off."""
    from femcontact.families.dislodging.pull import wedged_simulation

    scene = load_scene(SCENES / "dislodging_2d.toml",
                       ["mesh.resolution=0.5", "materials.hole.E=2969.2", "peg.insertion_depth=8.0",
                        "steps.0.moment=[1500.0]", "dislodging.case=2", "contact.normal='wall'"])
    simulation, _ = wedged_simulation(scene)
    row = simulation.history[-1]
    a = np.array([row["contact_A_Fx"], row["contact_A_Fy"]])
    b = np.array([row["contact_B_Fx"], row["contact_B_Fy"]])
    assert np.linalg.norm(a) > 50.0  # N/mm: wedged
    assert np.linalg.norm(a + b) <= 1e-6 * np.linalg.norm(a)
    for force in (a, b):
        assert abs(force[1]) <= scene["contact"]["mu"] * abs(force[0])


def loaded_contacts(settings: list) -> dict:
    """The 2-D thesis moment scene (d 50, D 50.05, l_d 7, Mz 1000 N*mm) at the end of its load step."""
    simulation = Simulation(load_scene(SCENES / "wedging_moment_2d.toml", settings), MPI.COMM_SELF)
    simulation.run()
    return [row for row in simulation.history if row["step"] == "load"][-1]


def test_quadratic_elements_along_the_wall_s_normal_take_the_corner_elements_direction():
    """With linear elements the peg's sharp corners are node-to-segment slave points, pushing along
    the wall's normal (the model that reproduces the thesis); quadratic elements have none, and
    their wall nodes see the peg's flank, 0.46 deg off the wall. Contact elements 30 um: along the
    wall's normal the force at A is within 0.1 % of the corner elements' (measured 61.57 against
    61.51 N/mm) and B's force leans from the wall by mu (0.2000); along the peg's normal it is
    2.3 % lower and B leans by mu + tan(tilt) (0.2084; docs/wedging_3d.md, "Which direction the
    2-D model takes")."""
    corners = loaded_contacts([])
    fine = ["mesh.degree=2", "mesh.contact_size=0.03", "mesh.contact_zone=1.0"]
    wall = loaded_contacts([*fine, "contact.normal='wall'"])
    body = loaded_contacts([*fine, "contact.normal='body'"])
    mu, tilt = 0.2, np.radians(body["tilt_deg"])
    assert wall["contact_A_force"] == pytest.approx(corners["contact_A_force"], rel=0.005)
    assert body["contact_A_force"] < 0.99 * corners["contact_A_force"]
    assert wall["contact_B_Fy"] / wall["contact_B_Fx"] == pytest.approx(mu, rel=0.005)
    assert body["contact_B_Fy"] / body["contact_B_Fx"] == pytest.approx(mu + np.tan(tilt), rel=0.005)
