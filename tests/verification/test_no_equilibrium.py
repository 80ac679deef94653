"""A load without a static equilibrium is an outcome, not a failure.

The wedging scene (d 40, D 40.1, l_d 5, a push [-5, 1] N on the peg top) needs mu >= 0.067 for
the rigid peg in two-point contact to hold the push (references.two_point_statics, verified in
test_two_point_statics.py). Without friction the peg cannot be held, let alone wedge: the run
ends with status `no_equilibrium`, naming the step, the load and that friction, and answers
"not wedged". Where the statics say an equilibrium exists, a solver failure stays `failed`.
"""
import json
import subprocess
import sys
from pathlib import Path

import pytest

from femcontact.families import load_scene
from femcontact.references import two_point_statics
from geometry.placement import peg_pose

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "wedging_2d.toml"
COARSE = ["mesh.resolution=0.5"]


def needed(scene: dict) -> float:
    pose = peg_pose(scene)
    return two_point_statics.friction_needed(two_point_statics.peg_in_hole_contacts(pose), [-5.0, 1.0],
                                             pose.points["peg_top"], 0.0)


def test_a_frictionless_peg_pushed_sideways_ends_without_equilibrium_and_not_wedged(tmp_path):
    out = tmp_path / "case"
    overrides = [*COARSE, "contact.mu=0", "solver.max_cuts=2"]
    code = subprocess.run([sys.executable, "-m", "femcontact", "run", str(SCENE), "--quiet", "--out", str(out),
                           *sum((["--set", o] for o in overrides), [])], cwd=ROOT).returncode
    result = json.loads((out / "result.json").read_text())
    assert code == 0 and result["status"] == "no_equilibrium", result["reason"]
    metrics = result["metrics"]
    assert metrics["wedged"] is False and metrics["analytic_wedged"] is False
    assert metrics["friction_needed"] == pytest.approx(needed(load_scene(SCENE, overrides)), rel=1e-5)
    assert 0.06 < metrics["friction_needed"] < 0.075 and metrics["mu"] == 0.0
    assert metrics["no_equilibrium_step"] == "load"
    reason = result["reason"]
    assert reason.startswith("step 'load' at t = ") and "at peg_top" in reason
    assert f"it needs mu >= {metrics['friction_needed']:.4g}, the scene has mu = 0" in reason


@pytest.mark.parametrize("mu, status", [(0.05, "no_equilibrium"), (0.08, "failed")])
def test_the_statics_not_the_stalled_residual_decide(tmp_path, monkeypatch, mu, status):
    """Newton made to fail at every increment: below the friction the push needs (0.067) the
    run ends without equilibrium, above it the failure is the solver's and stays a failure."""
    scene = load_scene(SCENE, [*COARSE, f"contact.mu={mu}", "solver.max_cuts=0"])
    result = run_with_newton_failing(scene, tmp_path, monkeypatch, status)
    if result:
        assert result["metrics"]["friction_needed"] == pytest.approx(needed(scene), rel=1e-5)


def run_with_newton_failing(scene: dict, tmp_path, monkeypatch, status: str) -> dict | None:
    """Run `scene` with every Newton solve failing: expect SimulationFailed (status 'failed', then
    None) or a result of `status` with no increment converged."""
    from femcontact.families.case import run_contact
    from femcontact.solver import newton
    from femcontact.solver.stepping import SimulationFailed

    def stalled(self, load, stiff_start=False):
        raise newton.NewtonFailure("no convergence in 40 iterations", [1.0, 0.99])

    monkeypatch.setattr(newton.SchurNewton, "solve", stalled)
    if status == "failed":
        with pytest.raises(SimulationFailed):
            run_contact(scene, tmp_path)
        return None
    result = run_contact(scene, tmp_path)
    assert result["status"] == status and result["metrics"]["increments"] == 0
    return result


INERTIA = [*COARSE, "contact.mu=0", "effects=['friction', 'plane_strain', 'inertia']"]


def run(tmp_path, overrides) -> dict:
    out = tmp_path / "case"
    code = subprocess.run([sys.executable, "-m", "femcontact", "run", str(SCENE), "--quiet", "--out", str(out),
                           *sum((["--set", o] for o in overrides), [])], cwd=ROOT).returncode
    assert code == 0
    return json.loads((out / "result.json").read_text())


def test_with_inertia_a_pull_without_equilibrium_runs_on_until_the_peg_leaves_contact(tmp_path):
    """A frictionless peg pulled along +y: an axial pull needs mu >= l_d / d (= 5 / 40, the wedging
    bound l_max = mu d read backwards); with inertia the peg runs on and leaves both contacts."""
    result = run(tmp_path, [*INERTIA, "steps.0.force=[0.0, 5.0]", "steps.0.duration=0.004", "steps.0.increments=4"])
    metrics = result["metrics"]
    assert result["status"] == "no_equilibrium" and metrics["run_on"] == "left_contact"
    assert metrics["friction_needed"] == pytest.approx(5.0 / 40.0, rel=1e-5)
    assert metrics["run_on_time"] < 0.004 and metrics["wedged"] is False
    assert "with inertia it ran on: the peg left contact at t = " in result["reason"]


def test_with_inertia_a_push_without_equilibrium_says_the_step_ended_with_the_peg_moving(tmp_path):
    result = run(tmp_path, [*INERTIA, "steps.0.duration=0.002", "steps.0.increments=2"])
    metrics = result["metrics"]
    assert result["status"] == "no_equilibrium" and metrics["run_on"] == "step_end"
    assert metrics["run_on_time"] == pytest.approx(0.002) and metrics["increments"] == 2
    assert metrics["friction_needed"] == pytest.approx(needed(load_scene(SCENE, INERTIA)), rel=1e-5)
    assert "the step ended, the peg still moving at t = 0.002 s" in result["reason"]


# A push down and to the left (|Fy / Fx| = 0.56) on a peg leaning in two-point contact: the rigid
# two-point statics hold it with mu 0.14, but only with a preload at the tip's contact, which this
# load opens (its moment about the mouth corner turns the peg upright). Upright against the left
# wall the load's moment cannot be balanced, so the peg turns on into the opposite lean, which the
# load opens too: the peg rocks between the leans and slides (with inertia it slides down 0.6 mm
# in 10 ms; docs/stability.md).
SLIDING = ["mesh.resolution=0.35", "contact.mu=0.5002", "hole.width=40.04824", "peg.insertion_depth=5.914",
           "materials.hole.nu=0.2924", "steps.0.force=[-3.333, -1.87]", "solver.max_cuts=2"]


def test_a_push_that_opens_the_tip_contact_and_rocks_the_peg_ends_without_equilibrium(tmp_path):
    scene = load_scene(SCENE, SLIDING)
    held = two_point_statics.placement_friction_needed(scene, [-3.333, -1.87], 0.0, "peg_top")
    assert held == pytest.approx(0.1414, abs=1e-4)  # the rigid two-point statics alone: held (mu 0.5002)
    result = run(tmp_path, SLIDING)
    metrics = result["metrics"]
    assert result["status"] == "no_equilibrium", result["reason"]
    assert metrics["friction_needed"] is None and metrics["wedged"] is False
    assert "turns the peg into the opposite lean): no friction holds it there" in result["reason"]


# A push of 76 N up and to the left on the top of a peg inserted 0.53 mm: the rigid two-point
# statics hold it with mu 0.0097 (the scene has 0.3775), through contact forces near 2000 N on a
# 0.53-mm lever. The elastic blocks give way under them and the load levers the peg up along the
# walls: with inertia it leaves both contacts at 75 % of the push (docs/stability.md), and
# pseudo-transient continuation carries it up by more than its insertion depth.
LIFTED = ["mesh.resolution=0.35", "contact.mu=0.3775", "hole.width=40.002656", "peg.insertion_depth=0.5342",
          "materials.hole.nu=0.3931", "steps.0.force=[-72.45, 22.27]", "steps.0.increments=1", "solver.max_cuts=0"]


def test_a_push_that_levers_the_peg_out_of_the_hole_ends_without_equilibrium(tmp_path):
    scene = load_scene(SCENE, LIFTED)
    assert two_point_statics.placement_friction_needed(scene, [-72.45, 22.27], 0.0, "peg_top") < 0.01
    result = run(tmp_path, LIFTED)
    assert result["status"] == "no_equilibrium", result["reason"]
    assert result["metrics"]["friction_needed"] is None and result["metrics"]["mu"] == 0.3775
    reason = result["reason"]
    assert "lifts the peg out of the hole: under pseudo-transient continuation it rose by " in reason
    rise = float(reason.split("it rose by ")[1].split(" mm")[0])
    assert rise > 0.5342


def test_with_inertia_a_push_without_equilibrium_lifts_the_peg_to_where_it_comes_to_rest(tmp_path):
    """The push [-5, 1] N at depth 5 needs mu >= 0.067 in two-point contact and less the shallower
    the peg (0.050 at depth 3): with mu = 0.06, applied at once, it lifts the peg, which slows as
    friction grows able to hold it and comes to rest higher up, where the two-point statics hold it."""
    overrides = [*COARSE, "contact.mu=0.06", "effects=['friction', 'plane_strain', 'inertia']",
                 "steps.0.amplitude=step", "steps.0.duration=0.03", "steps.0.increments=60"]
    result = run(tmp_path, overrides)
    metrics = result["metrics"]
    assert result["status"] == "no_equilibrium" and metrics["run_on"] == "at_rest", result["reason"]
    assert metrics["run_on_time"] < 0.03 and metrics["friction_needed"] > 0.06
    rise = metrics["load.rigid_y"]
    assert 0.5 < rise < 2.0  # mm: from depth 5 to where 0.06 suffices (about 4.3) or above
    rested = load_scene(SCENE, [*COARSE, f"peg.insertion_depth={5.0 - rise}"])
    assert two_point_statics.placement_friction_needed(rested, [-5.0, 1.0], 0.0, "peg_top") < 0.06
    assert "with inertia it ran on: the peg came to rest at t = " in result["reason"]


@pytest.mark.parametrize("mu, status", [(0.005, "no_equilibrium"), (0.02, "failed")])
def test_a_3d_couple_in_the_plane_of_the_lean_is_decided_by_the_statics_of_its_section(tmp_path, monkeypatch,
                                                                                         mu, status):
    """The 3-D wedging scene's couple needs mu >= tan(t / 2) = 0.011 (test_two_point_statics.py);
    with Newton made to fail, below it the run ends without equilibrium, above it stays a failure."""
    scene = load_scene(ROOT / "scenes" / "wedging_3d.toml", ["mesh.resolution=0.3", f"contact.mu={mu}",
                                                             "solver.max_cuts=0"])
    result = run_with_newton_failing(scene, tmp_path, monkeypatch, status)
    if result:
        assert result["metrics"]["friction_needed"] == pytest.approx(0.010963, rel=1e-3)
        assert "in two-point contact: it needs mu >= 0.01096, the scene has mu = 0.005" in result["reason"]


def test_a_peg_the_continuation_turns_over_has_tipped_out():
    """Seed 5's 1e212801c906: a couple of 2,520 N mm on a peg 3.73 mm deep. With inertia the peg
    tips out of the hole at t = 0.7477 s (docs/stability.md); quasi-statically, at resolution
    1.093, pseudo-transient continuation gives up at t = 0.7445 s having turned the peg by 2.39 rad
    and lifted it by 1.75 mm, less than its insertion depth. More than a quarter turn without
    coming to rest is the verdict; a smaller turn is not."""
    from types import SimpleNamespace

    import numpy as np

    from femcontact.families.case import carried_out

    scene = load_scene(SCENE, [*COARSE, "contact.mu=0.3542", "hole.width=40.1634", "peg.insertion_depth=3.728",
                               "steps.0.force=[]", "steps.0.moment=[2520.0]"])
    failure = SimpleNamespace(step=0, load=SimpleNamespace(time=0.7445, force=np.zeros(2), moment=np.array([1876.2])))

    def verdict(travel):
        return carried_out(SimpleNamespace(scene=scene, pseudo_travel={0: np.array(travel)}), failure)

    tipped = verdict([1.537, 1.749, 2.386])
    assert tipped["step"] == "load" and tipped["friction_needed"] is None and tipped["mu"] == 0.3542
    assert "couple 1876 N*mm) tips the peg over: under pseudo-transient continuation it turned by 137 deg" in tipped["load"]
    assert verdict([1.537, 1.749, 1.5]) is None  # 86 deg: not yet over
    assert "it rose by 3.8 mm, more than its insertion depth of 3.728 mm" in verdict([0.0, 3.8, 0.1])["load"]
