"""The linear solvers (solver/linear.py) give the Newton direction of the full factorisation.

At a state with active, sliding contact (the coarse 3-D wedged cylinder after its first load
increment; 2-D wedging with its rigid corners), the Newton direction (du, dr) from
`ContactUpdate` (bulk factored once, the contact by Woodbury) must equal the one from
`Factorization` (the whole Jacobian factored) to round-off: 1e-8 relative, where both are
exact solves of the same system with condition numbers up to ~1e6. The update is also
checked when it must fall back to the full factorisation (a contact set above its rank cap),
and to be used only where the bulk stiffness is state-independent. The iterative solver (GMRES
and algebraic multigrid, `solver.linear = "iterative"`) stops at a residual 1e-6 of the
right-hand side's: its direction may differ by that times the preconditioned operator's
condition number (tens for multigrid), so it is held to 1e-4; a whole run with it must
reach the same converged states as the direct solver's, to Newton's tolerance (1e-9 relative
of the load) plus that of the increments' paths (1e-6).
"""
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.config.scene import SOLVER
from femcontact.errors import InputError
from femcontact.solver import linear
from femcontact.solver.linear import ContactUpdate, Factorization, _mat_solve, unit_columns
from femcontact.solver.stepping import Simulation

SCENES = Path(__file__).parents[2] / "scenes"


def directions(scene_file: str, overrides: list, max_rank=None, options=None, by_entries=False):
    """Newton directions after one converged increment (the next increment's first iteration),
    from the scene's own `ContactUpdate` (`by_entries`: by entries from its first iteration) and
    from a `Factorization` of the same problem with the PETSc `options` (default: the scene's,
    a direct solve)."""
    simulation = Simulation(load_scene(SCENES / scene_file, overrides))
    if by_entries:
        simulation.newton.linear.iterations_ahead = 0
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
    assert newton.linear.by_entries == by_entries
    update = (du.array.copy(), dr.copy(), newton.linear)
    newton.linear = Factorization(simulation.problem, options or simulation.options.petsc_options, "full_",
                                  newton._near_nullspace)
    du, dr = newton.direction(load, R_u, R_r)
    return update, (du.array.copy(), dr.copy())


@pytest.mark.parametrize("by_entries", [False, True])
@pytest.mark.parametrize("scene_file, overrides", [
    ("wedging_3d.toml", ["mesh.resolution=0.4"]),
    ("wedging_2d.toml", ["mesh.resolution=0.5"]),
    # PETSc's own LU: the update's unit columns as dense right-hand sides (MUMPS's are sparse, its
    # entries of the inverse)
    ("wedging_2d.toml", ["mesh.resolution=0.5", "solver.petsc_options={pc_factor_mat_solver_type='petsc'}"]),
])
def test_contact_update_matches_full_factorisation(scene_file, overrides, by_entries):
    (du, dr, linear), (du_full, dr_full) = directions(scene_file, overrides, by_entries=by_entries)
    assert not linear.use_full and 0 < len(linear.S) <= linear.max_rank
    assert np.linalg.norm(du - du_full) <= 1e-8 * np.linalg.norm(du_full)
    assert np.linalg.norm(dr - dr_full) <= 1e-8 * np.linalg.norm(dr_full)


def update_error(comm=MPI.COMM_WORLD, by_entries=False) -> float:
    """Largest difference between what the contact update holds of K_bulk^-1 (by columns: its
    columns K_bulk^-1 e_s from MUMPS's sparse right-hand side; by entries: (K_bulk^-1)[S, S] from
    MUMPS's entries of the inverse) and the same solved as dense right-hand sides, relative to
    the largest entry, on the coarse 3-D wedged cylinder after its first increment (whose solves
    came after them: MUMPS solves again once it has given entries of the inverse)."""
    simulation = Simulation(load_scene(SCENES / "wedging_3d.toml", ["mesh.resolution=0.4"]), comm)
    update = simulation.newton.linear
    if by_entries:
        update.iterations_ahead = 0
    step = simulation.scene["steps"][0]
    dt = step["duration"] / step["increments"]
    simulation.increment(simulation.schedule.load(0, dt, dt))
    dense = _mat_solve(update.ksp, list(unit_columns(update.S, update.Kb).T), update.Kb)
    held, expected = (update.G, update._rows_of_S(dense)) if by_entries else (update.Z, dense)
    assert comm.allreduce(update.by_entries == by_entries and len(update.S) > 50 and held.shape == expected.shape,
                          op=MPI.LAND)
    return comm.allreduce(float(np.abs(held - expected).max()), op=MPI.MAX) / \
        comm.allreduce(float(np.abs(expected).max()), op=MPI.MAX)


@pytest.mark.parametrize("by_entries", [False, True])
def test_update_holds_the_dense_solves(by_entries):
    """Both are exact solves with one factor; they differ by the order of round-off (1e-15)."""
    assert update_error(by_entries=by_entries) <= 1e-12


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


def test_iterative_solver_gives_the_direct_direction():
    (du, dr, _), (du_iterative, dr_iterative) = directions("wedging_3d.toml", ["mesh.resolution=0.4"],
                                                           options=linear.ITERATIVE_PETSC_OPTIONS)
    assert np.linalg.norm(du_iterative - du) <= 1e-4 * np.linalg.norm(du)
    assert np.linalg.norm(dr_iterative - dr) <= 1e-4 * np.linalg.norm(dr)


def step_ends(overrides: list) -> tuple[dict, object]:
    simulation = Simulation(load_scene(SCENES / "wedging_3d.toml", ["mesh.resolution=0.4"] + overrides))
    simulation.run()
    return simulation.step_end_rows(), simulation.newton.linear


def test_a_run_with_the_iterative_solver_reaches_the_direct_solvers_states():
    direct, direct_solver = step_ends([])
    iterative, iterative_solver = step_ends(["solver.linear='iterative'"])
    assert isinstance(direct_solver, ContactUpdate)
    assert iterative_solver.ksp.getType() == "gmres" and iterative_solver.ksp.getPC().getType() == "gamg"
    assert direct["release"]["contact_B_force"] > 25.0  # wedged: more than the couple's force 1000/40 N
    for step in ("load", "release"):
        for column in ("contact_A_Fx", "contact_A_Fz", "contact_B_Fx", "contact_B_Fz", "tilt_deg"):
            assert iterative[step][column] == pytest.approx(direct[step][column], rel=1e-6, abs=1e-6), (step, column)


def test_auto_chooses_the_iterative_solver_from_its_size(monkeypatch):
    assert f"from {linear.ITERATIVE_DOFS:,} unknowns" in SOLVER["linear"].doc  # the scene's documentation
    monkeypatch.setattr(linear, "ITERATIVE_DOFS", 1000)
    simulation = Simulation(load_scene(SCENES / "wedging_3d.toml", ["mesh.resolution=0.4"]))
    assert simulation.dofs >= 1000
    assert simulation.newton.linear.ksp.getType() == "gmres"


def test_an_unknown_linear_solver_is_refused():
    with pytest.raises(InputError, match="solver.linear"):
        load_scene(SCENES / "wedging_3d.toml", ["solver.linear='cholesky'"])
