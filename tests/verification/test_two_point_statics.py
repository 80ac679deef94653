"""Statics of a rigid peg in two-point contact (femcontact.references.two_point_statics) against
the wedging condition (the thesis, ch. 3) and against contact forces built inside the friction cones."""
import math
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.references import two_point_statics as statics
from geometry.placement import peg_pose

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_2d.toml"


def pose(depth: float, clearance: float = 1e-8, width: float = 40.0):
    scene = load_scene(SCENE,
                       [f"peg.insertion_depth={depth}", f"hole.width={width * (1 + clearance)}"])
    return peg_pose(scene)


@pytest.mark.parametrize("depth", [2.0, 5.0, 9.0])
def test_a_push_along_the_axis_needs_the_wedging_friction(depth):
    """Pushed straight in (or pulled straight out) at the peg top, the peg in two-point contact
    jams exactly in the wedging range l < mu d (the thesis, ch. 3): it needs mu = l/d, to the order of
    the tilt (here 1e-8 rad; the contact forces grow without bound towards that limit)."""
    placed = pose(depth)
    contacts = statics.peg_in_hole_contacts(placed)
    axis = placed.rotation @ np.array([0.0, 1.0])
    for sign in (-1.0, 1.0):
        needed = statics.friction_needed(contacts, sign * axis, placed.points["peg_top"], 0.0)
        assert needed == pytest.approx(depth / 40.0, rel=1e-5)


def test_a_couple_the_way_the_peg_leans_needs_no_friction_and_the_other_way_the_wedging_friction():
    """Counter-clockwise (the top to -x, the way the peg leans) the normal forces alone balance
    the couple, up to the tilt (the normals are parallel to within it). Clockwise only friction
    can, with normal forces growing without bound: the peg jams in the wedging range, mu > l/d."""
    placed = pose(5.0, clearance=1e-5)
    contacts = statics.peg_in_hole_contacts(placed)
    top = placed.points["peg_top"]
    assert 0 < statics.friction_needed(contacts, [0.0, 0.0], top, 100.0) <= placed.tilt
    assert statics.friction_needed(contacts, [0.0, 0.0], top, -100.0) == pytest.approx(5.0 / 40.0, abs=2 * placed.tilt)


def test_loads_built_from_contact_forces_in_the_cones_have_an_equilibrium_and_the_friction_is_scale_free():
    placed = pose(5.0, clearance=1e-3)
    contacts = statics.peg_in_hole_contacts(placed)
    rng = np.random.default_rng(3)
    for _ in range(50):
        mu = rng.uniform(0.05, 0.8)
        force, moment = np.zeros(2), 0.0
        for point, normal in contacts:  # a contact force strictly inside its cone
            tangent = np.array([-normal[1], normal[0]])
            f = rng.uniform(0.1, 10) * (normal + rng.uniform(-0.99, 0.99) * mu * tangent)
            force, moment = force + f, moment + point[0] * f[1] - point[1] * f[0]
        at = placed.points["peg_top"]
        couple = -moment - (at[0] * -force[1] - at[1] * -force[0])  # the load balancing them, applied at the top
        assert statics.has_equilibrium(contacts, -force, at, couple, mu)
        needed = statics.friction_needed(contacts, -force, at, couple)
        assert needed <= mu
        assert statics.friction_needed(contacts, -1e3 * force, at, 1e3 * couple) == pytest.approx(needed, rel=1e-5)


def case_scene(mu: float, width: float, depth: float, force: list) -> dict:
    return load_scene(SCENE, [f"contact.mu={mu}", f"hole.width={width}", f"peg.insertion_depth={depth}",
                              f"steps.0.force={force}"])


def test_a_load_that_presses_the_tip_corner_is_held_in_two_point_contact():
    """The scene's push [-5, 1] N turns the peg about the mouth corner into the tip's wall: the
    placement's own statics decide."""
    scene = load_scene(SCENE)
    needed, where = statics.reached_friction_needed(scene, [-5.0, 1.0], 0.0, "peg_top")
    assert where == "two-point contact"
    assert needed == statics.placement_friction_needed(scene, [-5.0, 1.0], 0.0, "peg_top")


def test_a_load_that_opens_the_tip_corner_is_held_upright_against_the_wall_by_friction_alone():
    """A push down and to the left whose moment about the mouth corner turns the peg upright: lying
    on the left wall the peg is held by friction exactly when mu >= |Fy / Fx| (the wall's normal
    takes Fx, friction Fy), whatever the two-point statics need (0.22 here)."""
    force = [-8.452, -0.7945]
    scene = case_scene(0.5115, 40.1043, 9.262, force)
    assert statics.placement_friction_needed(scene, force, 0.0, "peg_top") == pytest.approx(0.2203, abs=1e-4)
    needed, where = statics.reached_friction_needed(scene, force, 0.0, "peg_top")
    assert where == "upright against the wall of contact A"
    assert needed == pytest.approx(0.7945 / 8.452, rel=1e-5)


def test_a_load_that_opens_both_leans_is_held_nowhere():
    """Upright against the left wall this push's line of action passes beside the flank (its moment
    about the flank's lower end turns the peg on); in the opposite lean its moment about the other
    mouth corner opens that lean's tip contact: no configuration holds it at any friction."""
    force = [-3.333, -1.87]
    scene = case_scene(0.5002, 40.04824, 5.914, force)
    assert statics.reached_friction_needed(scene, force, 0.0, "peg_top") == (math.inf, "into the opposite lean")
    placed = peg_pose(scene)
    contacts = statics.peg_in_hole_contacts(placed)
    assert not statics.presses_tip(contacts, force, placed.points["peg_top"], 0.0)
    assert statics.presses_tip(contacts, [-5.0, 1.0], placed.points["peg_top"], 0.0)


def test_a_3d_peg_under_a_couple_in_the_plane_of_its_lean_has_the_statics_of_its_section():
    """The 3-D wedging scene's couple My = -1000 N mm leans the peg further (the 2-D couple +1000,
    `section_load`). Contact A's normal (the peg's side) is tilted by the lean t, B's (the wall)
    is not, so the couple leaves a vertical force N sin t that friction must carry at both:
    mu >= tan(t / 2). A couple about another axis leaves the plane: the model does not apply."""
    scene = load_scene(SCENE.parent / "wedging_3d.toml", ["mesh.resolution=0.3"])
    tilt = peg_pose(scene).tilt
    step = scene["steps"][0]
    assert statics.section_load(3, [0.0, 0.0, 0.0], step["moment"]) == ([0.0, 0.0], 1000.0)
    assert statics.step_friction_needed(scene, step) == pytest.approx(math.tan(tilt / 2), rel=1e-5)
    section = load_scene(SCENE, ["peg.width=40", "hole.width=40.1", "peg.insertion_depth=5", "steps.0.force=[]",
                                 "steps.0.moment=[1000]"])
    assert statics.step_friction_needed(section, section["steps"][0]) == statics.step_friction_needed(scene, step)
    assert statics.step_friction_needed(scene, {**step, "moment": [10.0, -1000.0, 0.0]}) is None
