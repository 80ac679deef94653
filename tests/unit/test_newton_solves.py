"""Every Newton solve of a run is counted by how it ended (`SchurNewton.solves`), in a result's
`info["newton_solves"]` (`python -m benchmarks.newton_solves` prints them)."""
import femcontact
from benchmarks.newton_solves import run_recorded
from femcontact.solver import newton


def test_the_counted_solves_add_up_to_the_runs_newton_iterations():
    """Wedging at a coarse mesh converges every increment by plain Newton: one plain solve per
    increment, their iterations the run's, none failed, their seconds within the solve time."""
    scene = femcontact.load_scene("scenes/wedging_2d.toml", {"mesh.resolution": 0.35})
    totals, result = run_recorded(scene)
    assert result.status == "ok"
    increments = sum(step["increments"] for step in scene["steps"])
    assert totals["plain"][:2] == (increments, result.info["newton_iterations"])
    assert totals["continuation"][0] == totals["failed"][0] == 0
    assert 0 < totals["plain"][2] <= result.timings["solve"]


def test_a_failed_run_records_what_its_failed_solves_spent(tmp_path, monkeypatch):
    """A run whose every Newton solve fails after 40 iterations (`_iterate` made to fail) ends
    `failed`, and its result still says how many solves failed, with their 40 iterations each,
    and the time they took."""
    def failing(self, load, stiff_start=False):
        raise newton.NewtonFailure("no convergence in 40 iterations", [1.0] * 41)

    monkeypatch.setattr(newton.SchurNewton, "_iterate", failing)
    scene = femcontact.load_scene("scenes/wedging_2d.toml", {"mesh.resolution": 0.35, "solver.max_cuts": 1})
    result = femcontact.run(scene, out=tmp_path / "case", quiet=True)
    assert result.status == "failed"
    failed = result.info["newton_solves"]["failed"]
    assert failed["solves"] > 0 and failed["iterations"] == 40 * failed["solves"]
    assert 0 <= failed["seconds"] <= result.timings["solve"]
    assert result.info["newton_solves"]["plain"]["solves"] == 0
