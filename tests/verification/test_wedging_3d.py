"""3-D wedging: a rigid cylindrical peg wedged in a round hole by a couple and released.

One coarse case (scenes/wedging_3d.toml at resolution 0.5, ~3k dofs, ~25 s on one rank):
after the couple is removed the peg must stay wedged: both contact zones keep a resultant
(well above the 2 % floor of femcontact.wedging), the released state needs no contact
stabilisation, the two resultants balance (no external load) and lie on the line through
the two contact centres (a wedged peg is a two-force body). The same with the peg's rims
rounded (`peg.corner_radius` = 1 mm, ~10 s): wedged alike, and contact B found on the rim's
torus where the placement puts it, which the sharp rim misses on this mesh; and with a 1 mm x
45 deg tip chamfer (`peg.chamfer_width`, a cone): wedged alike; and with the contact force
along the peg's normal (`contact.normal = "body"`; the scene names the wall's): wedged alike.
Under the couple the rim sliding down the wall at B is held by the wall's normal force and
Coulomb friction, so contact B's force leans from the wall's normal by mu (the peg's normal
tilts it with the peg's flank). See docs/wedging_3d.md.
"""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_3d.toml"


def zone(row: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(resultant force on the block, force centre) of contact zone `name` (N, mm)."""
    force = np.array([row[f"contact_{name}_F{a}"] for a in "xyz"])
    centre = np.array([row[f"contact_{name}_{a}"] for a in "xyz"])
    return force, centre


def run(*overrides: str) -> Simulation:
    simulation = Simulation(load_scene(SCENE, ["mesh.resolution=0.5", *overrides]))
    simulation.run()
    return simulation


@pytest.fixture(scope="module")
def released():
    return run()


@pytest.fixture(scope="module")
def rounded():
    return run("peg.corner_radius=1.0")


@pytest.fixture(scope="module")
def chamfered():
    return run("peg.chamfer_width=1.0")


@pytest.fixture(scope="module")
def peg_normal():
    return run("contact.normal='body'")


def test_couple_increases_the_tilt(released):
    rows = released.step_end_rows()
    assert rows["load"]["tilt_deg"] > np.degrees(released.problem.model.rigid["tilt"])


@pytest.mark.parametrize("case", ["released", "rounded", "chamfered", "peg_normal"])
def test_released_peg_stays_wedged(case, request):
    row = request.getfixturevalue(case).step_end_rows()["release"]
    moment = 1000.0
    arm = 40.0  # ~ l_2P: the force of the couple is ~25 N
    f_a, c_a = zone(row, "A")
    f_b, c_b = zone(row, "B")
    assert np.linalg.norm(f_a) > 0.02 * moment / arm
    assert row["stabilization_force"] == 0.0
    assert np.linalg.norm(f_a + f_b) < 1e-3 * np.linalg.norm(f_a)
    line = c_b - c_a
    for force in (f_a, f_b):
        cosine = abs(force @ line) / (np.linalg.norm(force) * np.linalg.norm(line))
        assert np.degrees(np.arccos(min(cosine, 1.0))) < 1.0


def test_rounded_rim_touches_the_wall_where_placed(rounded):
    """Contact B's force centre lies within 0.1 mm (a tenth of the contact elements, h_c = 1 mm)
    of the rounded rim's tangent point on the wall, as placed (z = -2.862 mm; measured 0.027 mm
    above it). The sharp rim's centre lies 0.39 mm above its edge on this mesh (docs/wedging_3d.md)."""
    placed = rounded.problem.model.points["contact_B"]
    _, centre = zone(rounded.step_end_rows()["release"], "B")
    assert placed[2] == pytest.approx(-2.8618, abs=1e-4)
    assert abs(centre[2] - placed[2]) < 0.1


def test_a_peg_without_stiffness_where_it_starts_follows_the_load():
    # placed in two-point contact, the peg touches the block with no force: it has no stiffness,
    # and a plain Newton step would move it a whole contact element (1 mm here, 20 x the radial
    # clearance of 0.05 mm), from where Newton can settle in another configuration (on the
    # 288k-unknown mesh: the peg rolled about the line through its contacts and jammed, 602 N
    # instead of 15.8 N). The increment starts from the stabilised continuation instead, and
    # with friction (several stick-slip states may hold the load) it takes every factor in turn.
    from femcontact.solver.newton import NewtonFailure
    from solver_trace import EVERY_STABILIZATION_FACTOR, stabilization_factors_taken

    scene = load_scene(SCENE, ["mesh.resolution=0.5", "steps.0.increments=1", "steps.0.moment=[0, -200, 0]"])
    simulation = Simulation(scene)
    load = simulation.schedule.load(0, scene["steps"][0]["duration"], scene["steps"][0]["duration"])
    start = simulation.problem.state()
    simulation.problem.begin_increment(load)
    with pytest.raises(NewtonFailure, match="no stiffness"):
        simulation.plain_solve(load)
    simulation.problem.restore(start)
    factors = stabilization_factors_taken(simulation)
    simulation.run_step(0, scene["steps"][0])
    row = simulation.history[-1]
    assert simulation.stabilized_increments == 1
    assert simulation.problem.path_dependent()
    assert factors[:-1] == EVERY_STABILIZATION_FACTOR  # then the spring off
    assert row["stabilization_force"] == 0.0  # the exact equations hold at the end
    # the peg stays in its two-point state: the force of the first fifth of the couple is that of
    # the finer meshes (16.80-16.94 N on curved P2 elements from 20k to 308k unknowns, the ladder
    # wedging_3d_p2_wall of docs/wedging_3d.md) within 5 % (this 3k-dof mesh puts contact B
    # 0.39 mm above the rim: 17.43 N), not a jammed state's
    force_a, _ = zone(row, "A")
    force_b, _ = zone(row, "B")
    assert np.linalg.norm(force_a) == pytest.approx(16.9, rel=0.05)
    assert np.linalg.norm(force_a + force_b) < 1e-6 * np.linalg.norm(force_a)  # balanced: no other load


def test_the_sliding_rim_leans_from_the_wall_by_the_friction_coefficient(released, peg_normal):
    """Under the couple the peg turns and its rim slides down the wall at B: the wall's force is
    its normal force and mu times it along the wall, so Fz / |F_horizontal| = mu (Coulomb's bound,
    reached where the rim slides; measured 0.35 % below it on this mesh, where some of B's nodes
    stick: 1 % allowed). Along the rigid body's normal the sharp rim is seen by the flank's
    normal, tilted with the peg: mu + tan(tilt) = 0.224 (measured 0.2251)."""
    mu = 0.2
    for simulation, expected in ((released, mu), (peg_normal, mu + np.tan(np.radians(1.37)))):
        force, _ = zone(simulation.step_end_rows()["load"], "B")
        assert abs(force[2]) / np.hypot(force[0], force[1]) == pytest.approx(expected, rel=0.01)


def test_committing_friction_at_the_mouth_edge_keeps_the_converged_equilibrium():
    """Tetrahedra along the hole's mouth edge have two contact facets (the mouth and the wall)
    that share the edge's nodes, their friction anchors and the trial traction; each facet clips
    it to its own bound mu p. Committing the larger of the two tractions keeps every increment's
    converged equilibrium (measured with their average instead: 0.7 to 3.8 N of force and up to
    51 N mm of moment left after each commit of this scene). Load step only, resolution 0.5."""
    from femcontact.effects.friction import contact_layers

    simulation = Simulation(load_scene(SCENE, ["mesh.resolution=0.5", "steps=[{name='load', increments=5, "
                                                                      "moment=[0.0, -1000.0, 0.0]}]"]))
    problem, newton, commit = simulation.problem, simulation.newton, simulation.problem.commit
    assert len(contact_layers(problem)) >= 2  # the mesh has elements with two contact facets
    residuals = []

    def checked_commit(dt):
        load = newton._assembled[0]
        commit(dt)
        R_u, R_r, scale = newton.assemble_residual(load)
        residuals.append((newton.force_norm(R_u, R_r), newton.tolerance(scale)))

    problem.commit = checked_commit
    simulation.run()
    assert len(residuals) == 5
    assert all(after <= tolerance for after, tolerance in residuals), residuals
