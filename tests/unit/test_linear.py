"""The low-rank contact update (solver/linear.py) gives the Newton direction of the full factorisation.

At a state with active, sliding contact (the coarse 3-D wedged cylinder after its first load
increment; 2-D wedging with its rigid corners), the Newton direction (du, dr) from
`ContactUpdate` (bulk factored once, the contact by Woodbury) must equal the one from
`Factorization` (the whole Jacobian factored) to round-off: 1e-8 relative, where both are
exact solves of the same system with condition numbers up to ~1e6. The update is also
checked when it must fall back to the full factorisation (a contact set above its rank cap),
and to be used only where the bulk stiffness is state-independent.
"""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.solver.linear import ContactUpdate, Factorization
from femcontact.solver.stepping import Simulation

SCENES = Path(__file__).parents[2] / "scenes"


def directions(scene_file: str, overrides: list, max_rank=None):
    """Newton directions after one converged increment (the next increment's first iteration),
    from the scene's own `ContactUpdate` and from a `Factorization` of the same problem."""
    simulation = Simulation(load_scene(SCENES / scene_file, overrides))
    step = simulation.scene["steps"][0]
    dt = step["duration"] / step["increments"]
    simulation.increment(simulation.schedule.load(0, dt, dt))
    load = simulation.schedule.load(0, 2 * dt, dt)
    newton = simulation.newton
    assert isinstance(newton.linear, ContactUpdate)
    if max_rank is not None:
        newton.linear.max_rank = max_rank
    R_u, R_r, _ = newton.assemble_residual(load)
    du, dr = newton.direction(load, R_u, R_r)
    update = (du.array.copy(), dr.copy(), newton.linear)
    newton.linear = Factorization(simulation.problem, simulation.options.petsc_options, "full_")
    du, dr = newton.direction(load, R_u, R_r)
    return update, (du.array.copy(), dr.copy())


@pytest.mark.parametrize("scene_file, overrides", [
    ("wedging_3d.toml", ["mesh.resolution=0.4"]),
    ("wedging_2d.toml", ["mesh.resolution=0.5"]),
])
def test_contact_update_matches_full_factorisation(scene_file, overrides):
    (du, dr, linear), (du_full, dr_full) = directions(scene_file, overrides)
    assert not linear.use_full and 0 < len(linear.S) <= linear.max_rank
    assert np.linalg.norm(du - du_full) <= 1e-8 * np.linalg.norm(du_full)
    assert np.linalg.norm(dr - dr_full) <= 1e-8 * np.linalg.norm(dr_full)


def test_contact_update_falls_back_above_its_rank_cap():
    (du, dr, linear), (du_full, dr_full) = directions("wedging_2d.toml", ["mesh.resolution=0.5"], max_rank=0)
    assert linear.use_full
    assert np.linalg.norm(du - du_full) <= 1e-12 * np.linalg.norm(du_full)


def test_state_dependent_bulk_is_factored_every_iteration():
    """Large strain: the bulk stiffness depends on u, so no cached factorisation."""
    scene = load_scene(SCENES / "wedging_2d.toml", ["mesh.resolution=0.5", "effects=['friction', 'plane_strain', 'large_strain']"])
    simulation = Simulation(scene)
    assert simulation.problem.forms.jacobian_bulk is None
    assert isinstance(simulation.newton.linear, Factorization)
