"""Load amplitudes (ramp, step, pulse trains) and the inertia component against exact motion."""
import numpy as np
import pytest

from femcontact.families.hertz import benchmark as hertz
from femcontact.problem.loading import pulse
from femcontact.families import resolve_scene
from femcontact.solver.stepping import Simulation


@pytest.mark.parametrize("shape, area", [("triangle", 0.5), ("square", 1.0), ("haversine", 0.5)])
def test_pulse_area_per_period(shape, area):
    """Mean of one period = duty * (shape's mean); 50 Hz, duty 0.4."""
    t = np.linspace(0, 0.02, 20001)[:-1]
    values = np.array([pulse(x, 50.0, 0.4, shape) for x in t])
    assert values.mean() == pytest.approx(0.4 * area, rel=1e-3)
    assert values.max() == pytest.approx(1.0, rel=1e-3) and values[t >= 0.4 * 0.02].max() == 0.0


def test_thesis_pulse_impulse():
    """The thesis, ch. 4: 50 Hz triangular pulses of 20.2 N, 4 pulses = 4 * 0.02 * 20.2 / 2 N*s."""
    t = np.linspace(0, 0.08, 80001)
    force = 20.2 * np.array([pulse(x, 50.0, 1.0, "triangle") for x in t])
    assert np.trapz(force, t) == pytest.approx(4 * 0.02 * 20.2 / 2, rel=1e-6)


def test_ramp_step_and_release_schedule():
    scene = hertz.scene(0.5)
    data = dict(scene, steps=[{"name": "up", "force": [0.0, -100.0], "load_point": "indenter"},
                              {"name": "hold", "force": [0.0, -100.0], "amplitude": "step", "load_point": "indenter"},
                              {"name": "down", "load_point": "indenter"}])
    simulation = Simulation(resolve_scene(data))
    schedule = simulation.schedule
    assert schedule.load(0, 0.25, 0.25).force[1] == pytest.approx(-25.0)
    assert schedule.load(1, 0.1, 0.1).force[1] == pytest.approx(-100.0)
    assert schedule.load(2, 0.5, 0.5).force[1] == pytest.approx(-50.0)


def test_free_rigid_body_follows_newton_second_law():
    """The cylinder indenter pulled off the block: y(t) = F t^2 / (2 m) with m = rho pi R^2
    (1 mm thick); Newmark starts from zero acceleration, an O(dt/T) = 1 % error at 100 steps."""
    data = dict(hertz.scene(0.5), effects=["inertia", "plane_strain"])
    data["materials"] = dict(data["materials"], indenter=dict(data["materials"]["indenter"], density=7.85e-9))
    data["dynamics"] = dict(data["dynamics"], newmark_beta=0.25, newmark_gamma=0.5)
    data["steps"] = [{"name": "pull", "duration": 1e-3, "increments": 100, "force": [0.0, 1.0],
                      "amplitude": "step", "load_point": "indenter"}]
    simulation = Simulation(resolve_scene(data))
    simulation.run()
    mass = 7.85e-9 * np.pi * 50.0 ** 2
    exact = 1.0 * 1e-3 ** 2 / (2 * mass)
    assert simulation.history[-1]["rigid_y"] == pytest.approx(exact, rel=0.02)
