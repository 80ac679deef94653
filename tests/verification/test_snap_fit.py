"""Snap fit (Whitney ch. 11): statics of a sliding flat taper, the spring's stiffness
against cantilever theory, jamming against the friction cone, on coarse meshes.

Convention (femcontact.references.snap_fit): alpha is the taper's half-angle from the insertion
axis, phi = atan(mu); the axial force on the pin is positive against insertion. Sliding:
F_ax / F_lat = tan(alpha + phi) inserting, tan(alpha - phi) withdrawing.
"""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.errors import InputError
from femcontact.references import snap_fit as reference

ROOT = Path(__file__).parents[2]
SCENE = ROOT / "scenes" / "snap_fit_2d.toml"
COARSE = ["spring.count=1", "mesh.resolution=0.6"]


def simulate(overrides: list[str]) -> dict:
    """Metrics of the contract scene with overrides, run in this process."""
    from femcontact.families.snap_fit.metrics import snap_fit_metrics
    from femcontact.solver.stepping import Simulation

    simulation = Simulation(load_scene(SCENE, COARSE + overrides))
    simulation.run()
    return snap_fit_metrics(simulation)


def test_contract_scene_runs_with_femcontact_run(tmp_path):
    """`femcontact run scenes/snap_fit_2d.toml` with the contract's keys writes the force ratios,
    equal to the statics of a flat interface with friction."""
    mu, angle = 0.3, 40.0
    command = [sys.executable, "-m", "femcontact", "run", str(SCENE), "--quiet", "--out", str(tmp_path),
               "--set", 'peg.nose="taper"', "--set", f"peg.nose_angle={angle}", "--set", f"contact.mu={mu}",
               *[arg for item in COARSE for arg in ("--set", item)]]
    subprocess.run(command, check=True, cwd=ROOT, timeout=600)
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["status"] == "ok", result["reason"]
    m = result["metrics"]
    alpha = math.radians(angle)
    assert m["insertion_force_ratio"] == pytest.approx((math.sin(alpha) + mu * math.cos(alpha))
                                                       / (math.cos(alpha) - mu * math.sin(alpha)), rel=1e-3)
    assert m["withdrawal_force_ratio"] == pytest.approx((math.sin(alpha) - mu * math.cos(alpha))
                                                        / (math.cos(alpha) + mu * math.sin(alpha)), rel=1e-3)
    assert not m["jammed"]
    # the shank: the final contact force is the spring's, friction adds mu times it axially
    assert m["insertion_force"][-1] == pytest.approx(mu * m["final_contact_force"], rel=1e-3)


@pytest.mark.parametrize("angle, mu", [(20.0, 0.1), (45.0, 0.4)])
def test_flat_taper_force_ratio_equals_statics(angle, mu):
    m = simulate([f"peg.nose_angle={angle}", f"contact.mu={mu}", "peg.nose_length=0.8"])
    alpha = math.radians(angle)
    assert m["insertion_force_ratio"] == pytest.approx(math.tan(alpha + math.atan(mu)), rel=1e-3)
    assert m["withdrawal_force_ratio"] == pytest.approx(math.tan(alpha - math.atan(mu)), rel=1e-3)


def test_the_concave_nose_goes_in_without_a_cut():
    """The pin's motion is all prescribed, so each increment starts from the last converged
    displacement plus the last increment's change (`Simulation._predict`): the concave nose of
    `make snap_fit` (steep at its end, 80 increments per step) goes in and back out without a cut.
    Started from the last converged state instead, 19 of its insertion increments were cut."""
    from femcontact.solver.stepping import Simulation

    simulation = Simulation(load_scene(SCENE, ["spring.count=1", "mesh.resolution=0.75", "steps.0.increments=80",
                                               "steps.1.increments=80", 'peg.nose="concave"', "peg.nose_length=0.3"]))
    simulation.run()
    steps = [row["step"] for row in simulation.history]
    assert steps.count("insert") == 80 and steps.count("withdraw") == 80


def test_lateral_stiffness_is_cantilever_theory():
    """Frictionless, small deflection (interference 0.15 mm = 3 % of L): the spring's force on the
    shank over the interference is 3EI/L^3 = E b h^3 / 4L^3 (Timoshenko's shear term, 0.3 % here,
    included). Quadratic elements, 3 across the thickness."""
    m = simulate(['effects=["plane_stress"]', "mesh.resolution=1.0"])
    scene = load_scene(SCENE, COARSE)
    spring, material = scene["spring"], scene["materials"]["spring"]
    k = reference.timoshenko_stiffness(material["E"], material["nu"], spring["thickness"], spring["length"],
                                       spring["width"])
    assert m["final_contact_force"] / spring["interference"] == pytest.approx(k, rel=5e-3)
    assert m["insertion_force"][-1] == pytest.approx(0.0, abs=1e-9)
    # the root carries the moment F L of the lateral force at the apex (height L): 6 F L / (b h^2)
    F = m["final_contact_force"] / spring["width"]
    assert m["root_stress"] == pytest.approx(6 * F * spring["length"] / spring["thickness"] ** 2, rel=1e-3)


def test_large_deflection_departs_from_the_rigid_arm_as_the_elastica_does():
    """Interference 1 mm on L = 5 (20 %), frictionless. The rigid-arm idealisation is linear: force
    k delta. With `large_strain` the FE force falls below the small-strain FE force by the ratio of
    the clamped elastica (with the pad's offset e = h/2 + pad = 1.35 mm) to k delta: 0.872. (The
    1.2 mm pad stiffens the spring's end by ~2 % in both FE runs; the ratio cancels it.)"""
    overrides = ["peg.width=4.0", "peg.nose_angle=45.0", "peg.nose_length=1.5", "spring.interference=1.0",
                 "spring.pad_height=1.2", "steps.0.motion.y=-1.0", "steps.1.motion.y=-0.9",
                 "steps.1.increments=1", "mesh.resolution=1.0"]
    large = simulate(['effects=["plane_stress", "large_strain"]'] + overrides)
    small = simulate(['effects=["plane_stress"]'] + overrides)
    scene = load_scene(SCENE, COARSE + overrides)
    spring, E = scene["spring"], scene["materials"]["spring"]["E"]
    elastica = reference.elastica_tip_force(E, spring["thickness"], spring["length"],
                                            spring["thickness"] / 2 + spring["pad_height"], 1.0, spring["width"])
    linear = reference.cantilever_stiffness(E, spring["thickness"], spring["length"], spring["width"]) * 1.0
    assert elastica / linear == pytest.approx(0.872, abs=0.002)
    assert large["final_contact_force"] / small["final_contact_force"] == pytest.approx(elastica / linear, rel=2e-2)


@pytest.mark.parametrize("angle, expected", [(55.0, False), (70.0, True), (80.0, True)])
def test_jamming_where_the_friction_cone_says(angle, expected):
    """mu = 0.3 (phi = 16.7 deg). 80 deg: the insertion force lies inside the friction cone
    (alpha + phi > 90 deg) and the apex sticks on the nose; 55 deg slides. 70 deg lies between
    the reduced model's bound, 1.5 (e/L) tan(alpha + phi) >= 1 (65.6 deg), and the plain cone
    (73.3 deg): there is no sliding equilibrium, Newton cycles between stick and slip at every cut,
    and the increment solved with every contact stuck first (`Simulation.locked_first_solve`)
    finds the stuck apex, an equilibrium of the real law. A short push, 0.015 mm past first touch
    in 0.0035 mm increments: the 80-degree nose's working part is only 0.026 mm long."""
    H = 0.15 if angle > 60 else 0.5
    m = simulate([f"peg.nose_angle={angle}", "contact.mu=0.3", f"peg.nose_length={H}", "peg.start_gap=0.02",
                  "steps.0.motion.y=-0.035", "steps.0.increments=10", "steps.1.motion.y=-0.035",
                  "steps.1.increments=1", "solver.max_cuts=3"])
    assert m["jammed"] is expected
    assert m["model_jammed"] is expected
    assert m["cone_jammed"] is (angle + math.degrees(math.atan(0.3)) >= 90)
    if expected:
        assert "inside the friction cone" in m["jam_reason"] and 0 < m["jam_depth"] < 0.015
    else:
        assert m["jam_reason"] is None
    assert m["stopped"] == ""  # the whole push ran


def test_bad_nose_is_refused():
    with pytest.raises(InputError, match="peg.nose_angle"):
        load_scene(SCENE, ["peg.nose=\"convex\"", "peg.nose_angle=50"])
    with pytest.raises(InputError, match="spring.interference"):
        load_scene(SCENE, ["spring.interference=0.4"])
    with pytest.raises(InputError, match="peg.nose_points"):
        load_scene(SCENE, ["peg.nose=\"points\"", "peg.nose_points=[[0.5, 0.0], [0.9, 1.0]]"])


def test_reduced_model_matches_fe_on_a_convex_nose():
    """The rigid-arm model (stiffness 3EI/L^3, coupling 1.5 e/L) against FE on a convex arc nose:
    insertion force against depth within 3 % of the peak."""
    from geometry.snap_fit import layout, nose_profile

    overrides = ['peg.nose="convex"', "peg.nose_angle=25.0", "contact.mu=0.2"]
    m = simulate(overrides)
    scene = load_scene(SCENE, COARSE + overrides)
    spring, E = scene["spring"], scene["materials"]["spring"]["E"]
    k = reference.cantilever_stiffness(E, spring["thickness"], spring["length"], spring["width"])
    depth = np.array(m["insertion_depth"])
    _, axial = reference.rigid_arm_forces(nose_profile(scene["peg"]), layout(scene).apex[0], k, 0.2,
                                          reference.coupling(spring), depth)
    force = np.array(m["insertion_force"])
    assert np.max(np.abs(force - axial)) < 0.03 * force.max()


def test_elastica_reference_reproduces_bisshopp_drucker():
    """Clamped elastica under a tip load perpendicular to the undeformed axis: for P L^2 / EI = 1
    the tip's lateral deflection is 0.3017 L (Bisshopp and Drucker 1945, Q. Appl. Math. 3:272)."""
    E, h, L = 125000.0, 0.3, 5.0
    P = E * h ** 3 / 12 / L ** 2
    assert reference.elastica_tip_force(E, h, L, 0.0, 0.3017 * L) == pytest.approx(P, rel=2e-4)


def test_constant_force_nose_halves_the_taper_peak_in_the_reduced_model():
    """Whitney's constant-force nose of the taper's working length (closed form for the reduced
    model, 24 points): its insertion force stays within 12 % of the design force F over the middle
    80 % of the stroke and peaks 42 % below the 30-degree taper's at equal final contact force."""
    from femcontact.families.snap_fit import design
    from femcontact.families.snap_fit.metrics import reduced_model

    scene = load_scene(SCENE, ["spring.count=1"])
    nose = design.constant_force(scene, design.taper_stroke(scene))
    _, force = design.forces(scene, nose["points"])
    middle = force[len(force) // 10: -len(force) // 10]
    assert np.all(np.abs(middle / nose["force"] - 1) < 0.12)
    taper = reduced_model(scene)["model_peak_insertion_force"]
    assert nose["peak"] / taper == pytest.approx(0.577, abs=0.01)
