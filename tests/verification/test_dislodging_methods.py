"""The dislodging load kinds beyond a plain pull (lateral pulses, moment pulses, pull plus shake) against exact
free-body solutions, and the pulse optimiser's verification step (femcontact.families.dislodging.methods)."""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.errors import InputError
from femcontact.families.dislodging.methods import apply_method, load_impulse, method_loads, peak_and_impulse

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "dislodging_methods_2d.toml"


def free_peg(pull_duration: float, observe_duration: float):
    """The dislodging peg centred in its hole (0.025 mm clear of both walls, no contact), at
    rest, its pull step `pull_duration` s; a DynamicSimulation whose dynamic part starts there."""
    from femcontact.solver.dynamics import DynamicSimulation

    scene = load_scene(SCENE, ["peg.placement=centred", f"steps.2.duration={pull_duration}",
                               f"steps.3.duration={observe_duration}"])
    return DynamicSimulation(scene, dynamic_from=2)


def integrate_free(simulation, dt):
    from femcontact.solver.dynamics import Event

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
    velocity = simulation.velocity
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
    velocity = simulation.velocity
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


@pytest.fixture(scope="module")
def wedged(tmp_path_factory):
    """The coarse wedged peg (resolution 0.5, thesis case 1), its puller and the checkpoint of
    its wedged state and quasi-static pull-out, from which the verifying runs start afresh."""
    from femcontact.families.dislodging.methods import MethodPuller

    checkpoint = tmp_path_factory.mktemp("wedged") / "checkpoint"
    scene = load_scene(SCENE, ["dislodging.task=optimise"])
    return scene, MethodPuller(scene, checkpoint=checkpoint), checkpoint


def test_twist_at_the_pullout_force_is_located_where_a_re_solve_fails(wedged):
    """Moment pulses of peak P d (the quasi-static pull-out P = 5.566 N on the coarse peg, twice the
    twist threshold of docs/dislodging_methods.md) open both contacts within the first rising half
    pulse (10 ms at 50 Hz). Bisecting the opening inside the first increment that sees it, a re-solve
    from that increment's start does not converge (the residual cycles 63, 66, 180 N): the integrator
    cuts that increment and locates the opening inside a shorter one."""
    scene, puller, _ = wedged
    row = puller.run("twist", puller.pullout["quasi_static_pullout_N"])
    assert row["dislodged"] and row["event"] == "open"
    assert 0 < row["dislodge_time_s"] < 0.5 / 50.0


def test_optimum_is_verified_by_a_fresh_simulation(wedged):
    """A tiny optimisation on the coarse wedged peg (one grid point per shape, 2 Nelder-Mead
    pulls each): the best pulse dislodges, and a fresh simulation (new solver, state read from
    the checkpoint) reproduces its impulse (the pulls are deterministic: only the solver's
    tolerance differs, 1e-6 allowed)."""
    from femcontact.families.dislodging.pulse_optimisation import optimise, verify

    scene, puller, checkpoint = wedged
    puller.settings.update(grid_hz=[50.0], grid_duty=[1.0], evaluations=2)
    rows = []
    optimum = optimise(puller, rows)
    assert len(rows) == optimum["evaluations"] and optimum["objective_impulse_Ns"] == min(r["objective_Ns"] for r in rows)
    best = min(rows, key=lambda r: r["objective_Ns"])
    assert best["dislodged"] and optimum["shape"] == best["shape"]
    checked = verify(scene, checkpoint, optimum)
    assert checked["verified_dislodged"] and checked["verified_relative_difference"] < 1e-6


def test_peak_optimum_is_a_threshold_verified_by_a_fresh_simulation(wedged):
    """A tiny peak-force optimisation (square pulses, 3 Nelder-Mead evaluations of a bisection
    to 0.1 N): no evaluation's threshold lies more than one bisection step (0.1 N) below the
    quasi-static pull-out P (a pulse does not get the wedged peg out with much less than the
    force that holds it statically; repeated square pulses at P itself do ratchet it out in
    make dislodging_methods_frequency), the optimum is the least of them, and a fresh simulation
    from the checkpoint dislodges at the optimal peak and not one bracket below it."""
    from femcontact.families.dislodging.pulse_optimisation import optimise_peak, verify_peak

    scene, puller, checkpoint = wedged
    puller.settings.update(peak_shapes=["square"], peak_evaluations=3, tolerance=0.1)
    rows = []
    optimum = optimise_peak(puller, rows)
    pullout = puller.pullout["quasi_static_pullout_N"]
    thresholds = [e["threshold_force_N"] for e in optimum["all_evaluations"]]
    assert len(thresholds) == 3 and min(thresholds) >= pullout - 0.1
    assert optimum["objective_peak_force_N"] == min(thresholds) and optimum["bracket_N"] <= 0.1 * (1 + 1e-9)
    checked = verify_peak(scene, checkpoint, optimum)
    assert checked["verified_dislodged"] and checked["verified_below_holds"]


def test_torque_across_the_peg_axis_is_against_the_wedging_moment():
    """3-D twist across the axis: the unit axis perpendicular to the peg's, opposite to the
    wedging moment (My = -1000 N*mm tilts the peg further: the unwedging torque is +y)."""
    from femcontact.families.dislodging.pullout_3d import across_axis

    tilt = np.radians(1.4)
    axis = np.array([-np.sin(tilt), 0.0, np.cos(tilt)])  # top leaning to -x, in the x-z plane
    assert across_axis([0.0, -1000.0, 0.0], axis) == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)
    skew = across_axis([0.0, -1000.0, 300.0], axis)  # a component along the axis is dropped
    assert abs(skew @ axis) < 1e-15 and skew @ [0.0, 1.0, 0.0] > 0 and np.linalg.norm(skew) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        across_axis([0.0, 0.0, 0.0], axis)


def test_3d_probes_stream_to_csv_and_resume(tmp_path):
    """The 3-D wedged cylinder on its coarse mesh (resolution 0.3, 1 rank): a small torque
    across the axis against the wedging moment is held (elastic, both contacts loaded), four
    times the friction torque mu (N_A + N_B) d / 2 is not, and the peg is seen to go (turned by
    more than the rise, not a Newton solve that stalled); each probe is in probes_3d.csv as soon
    as it is solved, and a new WedgedPeg3D on the same file answers from it without solving."""
    from femcontact.families.dislodging.pullout_3d import PROBES_FILE, WedgedPeg3D

    scene = load_scene(SCENE.with_name("dislodging_methods_3d.toml"), ["mesh.resolution=0.3"])
    probes = tmp_path / PROBES_FILE
    wedge = WedgedPeg3D(scene, probes=probes)
    c = wedge.contacts
    friction_torque = scene["contact"]["mu"] * (c["N_A"] + c["N_B"]) * scene["peg"]["width"] / 2
    assert wedge.holds(0.05 * friction_torque, "twist_across")
    assert not wedge.holds(4 * friction_torque, "twist_across")
    import csv

    with open(probes, newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert [(r["method"], r["holds"], r["goes"]) for r in rows] == [("twist_across", "True", "False"),
                                                                     ("twist_across", "False", "True")]
    assert "went on" in rows[1]["reason"]
    assert float(rows[0]["moved_mm"]) < scene["dislodging"]["rise"] and float(rows[0]["zone_A_N"]) > 0

    class Resumed(WedgedPeg3D):
        def probe(self, magnitude, method):
            raise AssertionError("solved again")

    again = Resumed(scene, probes=probes)
    assert again.resumed == 2
    assert again.holds(0.05 * friction_torque, "twist_across") and not again.holds(4 * friction_torque, "twist_across")
