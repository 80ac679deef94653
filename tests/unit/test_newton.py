"""The Newton solver's rigid step (solver/newton.py) is capped at one contact element; the
solver knows where several equilibria may hold one load (`Problem.path_dependent`).

A body without stiffness in some direction would otherwise leap through its partner: its
translations are capped at the contact element size h (mm) and its rotations at h / size
(rad, size the body's largest dimension), whichever of its dofs are held or prescribed.
"""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENES = Path(__file__).parents[2] / "scenes"


@pytest.mark.parametrize("held", [[], ["x"], ["x", "y"]])
def test_a_rigid_step_without_stiffness_is_capped_at_one_contact_element(held):
    overrides = ["mesh.resolution=0.35"] + [f"rigid_body.dofs.{name}='held'" for name in held]
    simulation = Simulation(load_scene(SCENES / "wedging_2d.toml", overrides))
    newton, problem = simulation.newton, simulation.problem
    free = problem.rigid.free
    n = int(free.sum())
    step = newton._rigid_step(np.zeros((n, n)), np.ones(n))  # no stiffness: the step is all cap
    lengths = np.abs(step) * problem.rigid_arms[free]  # mm: a rotation times the body's size
    assert lengths.max() == pytest.approx(problem.contact_size, rel=1e-12)
    rotation = step[-1]  # rz, free in every variant
    assert abs(rotation) == pytest.approx(problem.contact_size / problem.body_size, rel=1e-12)


@pytest.mark.parametrize("overrides, several_equilibria", [
    ([], True),  # Coulomb friction: several stick-slip states may hold one load
    (["contact.mu=0.0"], False),  # the friction effect named, but no friction acts
    (["effects=['plane_strain']"], False),
])
def test_the_solver_knows_where_an_answer_depends_on_its_path(overrides, several_equilibria):
    simulation = Simulation(load_scene(SCENES / "wedging_2d.toml", ["mesh.resolution=0.35", *overrides]))
    assert simulation.problem.path_dependent() is several_equilibria
