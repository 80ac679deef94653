"""`python -m benchmarks.newton_solves`: every Newton solve of a run is recorded, by how it ended."""
import femcontact
from benchmarks.newton_solves import run_recorded
from femcontact.solver import newton


def test_the_recorded_solves_add_up_to_the_runs_newton_iterations():
    """Wedging at a coarse mesh converges every increment by plain Newton: one recorded plain solve
    per increment, their iterations the run's, none failed, and the solver left unwrapped."""
    solve = newton.SchurNewton.solve
    scene = femcontact.load_scene("scenes/wedging_2d.toml", {"mesh.resolution": 0.35})
    totals, result = run_recorded(scene)
    assert result.status == "ok"
    increments = sum(step["increments"] for step in scene["steps"])
    assert totals["plain"][:2] == (increments, result.info["newton_iterations"])
    assert totals["continuation"][0] == totals["failed"][0] == 0
    assert newton.SchurNewton.solve is solve
