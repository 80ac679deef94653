"""Geometry: placement against the reference, refused inputs, meshes (sizes, tags, quality).

Meshes are coarse so the module runs in seconds. Quality is the radius ratio
(d * r_in / r_circ: 1 for an equilateral simplex, 0 for a degenerate one).
"""
import math

import numpy as np
import pytest
from mpi4py import MPI

from femcontact.errors import InputError
from femcontact.families import resolve_scene
from geometry import measures
from geometry.model import build, write
from geometry.placement import chamfer_height, peg_pose

MIN_QUALITY_2D = 0.5  # Frontal-Delaunay triangles; observed >= 0.62
MIN_QUALITY_3D = 0.05  # gmsh-optimised tetrahedra at coarse resolution; observed >= 0.08


def scene(dim=2, geometry="peg_in_hole", **sections):
    data = {"dim": dim, "geometry": geometry, "steps": [{"name": "load"}]}
    if geometry == "peg_in_hole":
        data["peg"] = {"width": 40, "length": 10, "insertion_depth": 5}
        data["hole"] = {"width": 40.1, "kind": "two_blocks" if dim == 2 else "single"}
    for key, value in sections.items():
        if isinstance(value, dict):
            data.setdefault(key, {}).update(value)
        else:
            data[key] = value
    return resolve_scene(data)


# --- placement ---------------------------------------------------------------

@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("l_d, tilt_deg", [(4, 1.6784), (5, 1.2560), (6, 1.0148)])
def test_two_point_tilt_matches_reference(dim, l_d, tilt_deg):
    # The reference tabulates 4 decimals that differ from the closed form by up to
    # 1.8e-4 deg (1.25618 vs 1.2560 at l_d = 5), so compare to 2e-4 deg.
    pose = peg_pose(scene(dim, peg={"insertion_depth": l_d}))
    assert math.degrees(pose.tilt) == pytest.approx(tilt_deg, abs=2e-4)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("l_d", [4, 5, 6, 10])
def test_two_point_contact_points(dim, l_d):
    d, D = 40.0, 40.1
    pose = peg_pose(scene(dim, peg={"insertion_depth": l_d}))
    a, b = pose.points["contact_A"], pose.points["contact_B"]
    assert a[0] == pytest.approx(-D / 2, abs=1e-12) and a[-1] == pytest.approx(0.0, abs=1e-12)
    assert b[0] == pytest.approx(D / 2, abs=1e-12)
    theta = pose.tilt
    assert b[-1] == pytest.approx(d * math.sin(theta) - l_d * math.cos(theta), abs=1e-12)
    assert np.linalg.norm(b - a) == pytest.approx(math.hypot(d, l_d), rel=1e-12)
    R = pose.rotation
    assert np.allclose(R.T @ R, np.eye(dim), atol=1e-15)
    axis = R[:, -1]
    assert axis[0] < 0  # the top leans towards -x
    assert np.allclose(pose.points["peg_top"], pose.origin + 10 * axis, atol=1e-12)


def test_gap_and_chamfers_move_the_contact_points():
    D, gap = 40.1, 0.01
    pose = peg_pose(scene(peg={"gap": gap}))
    assert pose.points["contact_B"][0] == pytest.approx(D / 2 - gap, abs=1e-12)
    assert pose.points["contact_A"][0] == pytest.approx(-D / 2 + gap, abs=1e-12)
    pose = peg_pose(scene(hole={"chamfer_width": 1.0, "chamfer_angle": 30.0}, peg={"chamfer_width": 0.5}))
    assert pose.points["contact_A"][1] == pytest.approx(-chamfer_height(1.0, 30.0), abs=1e-12)
    assert pose.points["contact_B"][0] == pytest.approx(D / 2, abs=1e-12)
    pose = peg_pose(scene(peg={"corner_radius": 0.5}))
    assert pose.points["contact_B"][0] == pytest.approx(D / 2, abs=1e-12)


def test_centred_placement():
    pose = peg_pose(scene(peg={"placement": "centred", "tilt": 0.2}))
    assert np.allclose(pose.points["peg_tip"], [0.0, -5.0])
    assert math.degrees(pose.tilt) == pytest.approx(0.2)


@pytest.mark.parametrize("sections, parameter", [
    ({"hole": {"width": 40.0}}, "hole.width"),
    ({"hole": {"width": 39.0}}, "hole.width"),
    ({"peg": {"insertion_depth": 12}}, "peg.insertion_depth"),
    ({"peg": {"insertion_depth": 2}}, "peg.insertion_depth"),  # below l_crit = 2.83
    ({"peg": {"placement": "centred", "tilt": 2.0}}, "peg.tilt"),
    ({"peg": {"chamfer_width": 20.0}}, "peg.chamfer_width"),
    ({"peg": {"gap": 0.05}}, "peg.gap"),
    ({"hole": {"chamfer_width": 25.0}}, "hole.chamfer_width"),
    ({"hole": {"chamfer_width": 1.0, "chamfer_angle": 1.0}}, "hole.chamfer_width"),
    ({"hole": {"depth": 3.0}}, "hole.depth"),
    ({"hole": {"block_width": -1.0}}, "hole.block_width"),
    ({"peg": {"corner_radius": 0.5}, "rigid": "hole"}, "peg.corner_radius"),
    ({"peg": {"corner_radius": 0.5, "chamfer_width": 1.0}}, "peg.corner_radius"),
    ({"hole": {"chamfer_width": 1.0}, "rigid": "hole"}, "hole.chamfer_width"),
])
def test_impossible_inputs_are_refused(sections, parameter):
    with pytest.raises(InputError, match=parameter.replace(".", r"\.")):
        scene(**sections)


def test_3d_needs_a_single_block():
    with pytest.raises(InputError, match=r"hole\.kind"):
        scene(3, hole={"kind": "two_blocks"})


# --- 2-D meshes ----------------------------------------------------------------

def check_tags(model, expected_facets, expected_cells):
    assert set(model.facets) == set(expected_facets)
    assert set(model.cells) == set(expected_cells)
    for name in model.facets:
        assert measures.measure(model, facet=name) > 0, name
    assert set(model.contact_facets) <= set(model.facets)
    assert set(model.supports) <= set(model.facets)


def test_two_blocks():
    model = build(scene(), MPI.COMM_WORLD)
    check_tags(model, ["wall_A", "wall_B", "mouth_A", "mouth_B", "support_A", "support_B"], ["block_A", "block_B"])
    assert measures.measure(model) == pytest.approx(2 * 20 * 20, rel=1e-12)
    assert measures.measure(model, cell="block_A") == pytest.approx(400, rel=1e-12)
    for name in model.facets:
        assert measures.measure(model, facet=name) == pytest.approx(20, rel=1e-12)
    assert model.supports == ["support_A", "support_B"]
    assert measures.min_quality(model.mesh) > MIN_QUALITY_2D
    assert model.h_contact == pytest.approx(20 / 250)
    assert model.rigid["shape"] == "rectangle" and model.rigid["half_width"] == 20


def test_chamfered_u_block_at_clearance_1e_4():
    D, bw, depth, bt, cw, angle = 50.005, 20.0, 20.0, 10.0, 1.0, 30.0
    h_c = chamfer_height(cw, angle)
    s = scene(peg={"width": 50.0}, hole={"width": D, "kind": "single", "chamfer_width": cw,
                                          "chamfer_angle": angle, "support": "bottom"})
    model = build(s, MPI.COMM_WORLD)
    check_tags(model, ["wall_A", "wall_B", "mouth_A", "mouth_B", "chamfer_A", "chamfer_B", "hole_bottom",
                       "support_A", "support_B"], ["block"])
    exact = (D + 2 * bw) * (depth + bt) - D * depth - 2 * (cw * h_c / 2)
    assert measures.measure(model) == pytest.approx(exact, rel=1e-12)
    assert measures.measure(model, facet="wall_A") == pytest.approx(depth - h_c, rel=1e-12)
    assert measures.measure(model, facet="chamfer_B") == pytest.approx(math.hypot(cw, h_c), rel=1e-12)
    assert measures.measure(model, facet="support_A") == pytest.approx(D / 2 + bw, rel=1e-12)
    assert measures.min_quality(model.mesh) > MIN_QUALITY_2D


def test_meshed_peg_at_clearance_1e_4():
    d, length, cw = 50.0, 10.0, 1.0
    s = scene(rigid="hole", peg={"width": d, "chamfer_width": cw}, hole={"width": 50.005})
    model = build(s, MPI.COMM_WORLD)
    check_tags(model, ["peg_left", "peg_right", "peg_tip", "peg_top", "peg_chamfer"], ["peg"])
    assert measures.measure(model) == pytest.approx(d * length - cw * cw, rel=1e-12)  # two 45-deg chamfers
    assert model.supports == ["peg_top"]  # held by the gripper; the rigid hole carries the loads
    assert model.rigid["shape"] == "hole" and model.rigid["half_width"] == pytest.approx(25.0025)
    assert measures.min_quality(model.mesh) > MIN_QUALITY_2D
    # the mesh is the placed peg: its tip corner sits on wall B
    x = model.mesh.geometry.x
    assert x[:, 0].max() == pytest.approx(50.005 / 2, abs=1e-9)


def test_resolution_refines_uniformly():
    coarse = build(scene(), MPI.COMM_WORLD)
    fine = build(scene(mesh={"resolution": 2.0}), MPI.COMM_WORLD)
    assert fine.h_contact == pytest.approx(coarse.h_contact / 2)
    ratio = fine.mesh.topology.index_map(2).size_global / coarse.mesh.topology.index_map(2).size_global
    assert 3.0 < ratio < 5.0  # halving every size quadruples the triangles


def test_block_2d_uniform_contact_zone(tmp_path):
    s = scene(geometry="block", mesh={"contact_size": 0.1, "contact_zone": 1.03})
    model = build(s, MPI.COMM_WORLD)
    check_tags(model, ["top", "bottom", "left", "right"], ["block"])
    assert measures.measure(model) == pytest.approx(100 * 50, rel=1e-12)
    x = model.mesh.geometry.x
    top = np.sort(x[(np.abs(x[:, 1]) < 1e-12) & (np.abs(x[:, 0]) < 1.0 + 1e-9), 0])
    assert np.allclose(top, np.arange(-10, 11) * 0.1, atol=1e-11)  # zone rounded to 10 elements
    assert 0.0 in top
    assert model.rigid["shape"] == "disc" and np.allclose(model.rigid["origin"], [0, 50])
    assert measures.min_quality(model.mesh) > MIN_QUALITY_2D
    write(model, tmp_path / "block.xdmf")
    assert (tmp_path / "block.h5").exists() and (tmp_path / "block.tags.json").exists()


# --- 3-D meshes ----------------------------------------------------------------

def test_hole_block_3d_volume():
    D, bw, depth, bt, cw = 40.1, 20.0, 20.0, 10.0, 1.0
    s = scene(3, mesh={"resolution": 0.3}, hole={"chamfer_width": cw})
    model = build(s, MPI.COMM_WORLD)
    check_tags(model, ["hole_wall", "hole_mouth", "hole_chamfer", "hole_bottom", "support"], ["block"])
    R, side = D / 2, D + 2 * bw
    cone = math.pi * cw / 3 * (R**2 + R * (R + cw) + (R + cw) ** 2)  # frustum of height cw (45 deg)
    exact = side**2 * (depth + bt) - math.pi * R**2 * (depth - cw) - cone
    # Facets are planar triangles with vertices on the curved surfaces, so the mesh
    # removes less than the exact hole: each wall strip of chord h loses at most the
    # sagitta h^2/(8R), so the excess is below the wall area (height depth) * h^2/(8R),
    # with h = the largest element size.
    h = (20 / 4) / 0.3  # default max size min(block_width, depth)/4 at resolution 0.3
    bound = 2 * math.pi * R * depth * h**2 / (8 * R)
    volume = measures.measure(model)
    assert 0 <= volume - exact < bound
    assert measures.measure(model, facet="support") == pytest.approx(4 * side * (depth + bt), rel=1e-12)
    assert measures.min_quality(model.mesh) > MIN_QUALITY_3D


def test_meshed_peg_3d_at_clearance_1e_4():
    s = scene(3, rigid="hole", mesh={"resolution": 0.3}, peg={"width": 50.0, "chamfer_width": 1.0},
              hole={"width": 50.005})
    model = build(s, MPI.COMM_WORLD)
    check_tags(model, ["peg_side", "peg_tip", "peg_top", "peg_chamfer"], ["peg"])
    assert model.points["peg_top"][2] > 0 > model.points["peg_tip"][2]
    assert measures.min_quality(model.mesh) > MIN_QUALITY_3D
    assert model.rigid["shape"] == "hole"


def test_block_3d():
    model = build(scene(3, geometry="block", mesh={"resolution": 0.3}), MPI.COMM_WORLD)
    check_tags(model, ["top", "bottom", "left", "right", "front", "back"], ["block"])
    assert measures.measure(model) == pytest.approx(100 * 100 * 50, rel=1e-12)
    assert measures.measure(model, facet="front") == pytest.approx(100 * 50, rel=1e-12)
    assert model.rigid["shape"] == "cylinder_y" and model.contact_facets == ["top"]
    assert measures.min_quality(model.mesh) > MIN_QUALITY_3D
