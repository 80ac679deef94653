"""The new load kinds of issue 14 (lateral pulses, moment pulses, pull plus shake) against exact
free-body solutions, and the pulse optimiser's verification step (femcontact.scenarios.dislodging_beyond)."""
from pathlib import Path

import numpy as np
import pytest

from femcontact.config.scene import load_scene
from femcontact.errors import InputError
from femcontact.scenarios.dislodging_beyond import apply_method, load_impulse, method_loads, peak_and_impulse

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "dislodging_beyond_2d.toml"


def free_peg(pull_duration: float, observe_duration: float):
    """The dislodging peg centred in its hole (0.025 mm clear of both walls, no contact), at
    rest, its pull step `pull_duration` s; a DynamicSimulation whose dynamic part starts there."""
    from femcontact.scenarios.dynamics import DynamicSimulation

    scene = load_scene(SCENE, ["peg.placement=centred", f"steps.2.duration={pull_duration}",
                               f"steps.3.duration={observe_duration}"])
    return DynamicSimulation(scene, dynamic_from=2)


def integrate_free(simulation, dt):
    from femcontact.scenarios.dynamics import Event

    outcome = simulation.integrate([2, 3], Event(rise=1.0, open_zones=False), dt_max=dt, dt_min=dt / 64,
                                   max_rise_per_increment=1.0)
    assert outcome.event is None and max(max(row[3:]) for row in outcome.trace) == 0.0  # never touched
    return outcome


@pytest.mark.parametrize("method, shape, duty", [("shake", "triangle", 1.0), ("pull_shake", "haversine", 0.5)])
def test_lateral_pulse_gives_a_free_peg_its_impulse_over_its_mass(method, shape, duty):
    """One 1 kHz lateral pulse (peak 1e-3 N; pull_shake adds a constant vertical 2e-3 N) on the
    free peg (m = 7.85e-9 x 50 x 15 = 5.89e-6 t): after the pulse m v = integral of F dt, exactly.
    Implicit Euler sums F(t_k) dt over uniform increments; for a symmetric triangle cut at its
    kinks and for a haversine (equispaced samples of sin^2 over its period, zero at both ends)
    that sum is the exact integral, so the tolerance is round-off (1e-9)."""
    period = 1e-3
    simulation = free_peg(period, 2e-4)
    loads = method_loads(method, 1e-3, -1.0, 50.0, 2e-3)
    apply_method(simulation, loads, method, 1 / period, duty, shape)
    integrate_free(simulation, period / 20)
    mass = simulation.problem.rigid.mass
    assert mass == pytest.approx(7.85e-9 * 50 * 15, rel=1e-12)
    force_impulse, moment_impulse = load_impulse(simulation.schedule, period + 2e-4)
    assert force_impulse[0] == pytest.approx(1e-3 * duty * period / 2, rel=1e-12)  # the pulse's area
    if method == "pull_shake":
        assert force_impulse[1] == pytest.approx(2e-3 * (period + 2e-4), rel=1e-12)  # the constant pull
    velocity = simulation.inertia.velocity
    assert velocity[0] == pytest.approx(force_impulse[0] / mass, rel=1e-9)
    assert velocity[1] == pytest.approx(force_impulse[1] / mass, rel=1e-9, abs=1e-12)
    # the moment of the lateral force about the reference point turns the peg: I w = arm x J
    assert abs(velocity[2]) > 0
    peak, impulse = peak_and_impulse(method, loads, force_impulse, moment_impulse, 50.0)
    assert peak == pytest.approx(np.hypot(1e-3, 2e-3 if method == "pull_shake" else 0.0), rel=1e-12)
    assert impulse == pytest.approx(np.linalg.norm(force_impulse), rel=1e-12)


def test_moment_pulse_gives_a_free_peg_its_angular_impulse_over_its_inertia():
    """Two 1 kHz triangular moment pulses (twist, magnitude 0.02 N: M = 0.02 x 50 = 1 N*mm,
    counter-clockwise) on the free peg: I w = angular impulse = 2 x 1 x 1e-3 / 2 N*mm*s, with
    I = m (50^2 + 15^2) / 12 = 1.34e-3 t*mm^2 about its centre; the peg does not translate
    (a pure couple), and the common units are M / d for the peak and the impulse."""
    period = 1e-3
    simulation = free_peg(2 * period, 1e-4)
    loads = method_loads("twist", 0.02, 1.0, 50.0, 0.0)
    apply_method(simulation, loads, "twist", 1 / period, 1.0, "triangle")
    integrate_free(simulation, period / 20)
    inertia = simulation.problem.rigid.mass_matrix[2, 2]
    assert inertia == pytest.approx(7.85e-9 * 50 * 15 * (50 ** 2 + 15 ** 2) / 12, rel=1e-12)
    force_impulse, moment_impulse = load_impulse(simulation.schedule, 2 * period + 1e-4)
    assert moment_impulse[0] == pytest.approx(1e-3, rel=1e-12) and not force_impulse.any()
    velocity = simulation.inertia.velocity
    assert velocity[2] == pytest.approx(1e-3 / inertia, rel=1e-9)
    assert np.abs(velocity[:2]).max() < 1e-9 * abs(velocity[2]) * 50
    assert peak_and_impulse("twist", loads, force_impulse, moment_impulse, 50.0) == pytest.approx((0.02, 1e-3 / 50))


def test_scene_keys_are_checked():
    with pytest.raises(InputError, match="dislodging.method"):
        load_scene(SCENE, ["dislodging.method=wiggle"])
    with pytest.raises(InputError, match="dislodging.magnitude_range"):
        load_scene(SCENE, ["dislodging.magnitude_range=[2.0, 1.0]"])
    with pytest.raises(InputError, match="pullout_3d"):
        load_scene(SCENE, ["dislodging.task=pullout_3d"])


def test_optimum_is_verified_by_a_fresh_simulation():
    """A tiny optimisation on the coarse wedged peg (one grid point per shape, 2 Nelder-Mead
    pulls each): the best pulse dislodges, and a fresh simulation (new solver, wedged again)
    reproduces its impulse (the pulls are deterministic: only the solver's tolerance differs,
    1e-6 allowed)."""
    from femcontact.scenarios.dislodging_beyond import BeyondPuller, optimise, verify

    overrides = ["dislodging.task=optimise", "dislodging.grid_hz=[50.0]", "dislodging.grid_duty=[1.0]",
                 "dislodging.evaluations=2", "dislodging.tolerance=0.05"]
    scene = load_scene(SCENE, overrides)
    rows = []
    optimum = optimise(BeyondPuller(scene), rows)
    assert len(rows) == optimum["evaluations"] and optimum["objective_impulse_Ns"] == min(r["objective_Ns"] for r in rows)
    best = min(rows, key=lambda r: r["objective_Ns"])
    assert best["dislodged"] and optimum["shape"] == best["shape"]
    checked = verify(scene, None, optimum)
    assert checked["verified_dislodged"] and checked["verified_relative_difference"] < 1e-6
