"""Snap fit in 3-D, coarse: scenes/snap_fit_3d.toml, the 2-D scene's spring swept across
its 1 mm width (quadratic tetrahedra, 2 across the thickness, 4 layers across the width) and a
blade pin whose flat-taper section is the same in every plane z = const. The checks of the 2-D
scene hold with forces in N over the whole width: the flat taper's force ratio equals the statics
of a sliding interface (alpha from the insertion axis, phi = atan(mu)), and the spring's lateral
stiffness is cantilever theory with the spring's width b: 3EI/L^3 = E b h^3 / (4 L^3)."""
import math
from pathlib import Path

import pytest

from femcontact.families import load_scene
from femcontact.references import snap_fit as reference

SCENE = Path(__file__).parents[2] / "scenes" / "snap_fit_3d.toml"
SHORT = ["steps.0.motion.y=-0.34", "steps.0.increments=10"]  # 0.05 gap, 0.26 on the taper, 0.03 on the shank


def simulate(overrides: list[str]) -> dict:
    from femcontact.families.snap_fit.metrics import snap_fit_metrics
    from femcontact.solver.stepping import Simulation

    simulation = Simulation(load_scene(SCENE, overrides))
    simulation.run()
    return snap_fit_metrics(simulation)


def test_3d_flat_taper_force_ratio_equals_statics():
    """30 deg taper, mu 0.2, in and back out over the taper (withdrawal to 0.05 mm past first touch)."""
    m = simulate(SHORT + ["steps.1.motion.y=-0.1", "steps.1.increments=6"])
    alpha, phi = math.radians(30.0), math.atan(0.2)
    assert m["insertion_force_ratio"] == pytest.approx(math.tan(alpha + phi), rel=1e-3)
    assert m["withdrawal_force_ratio"] == pytest.approx(math.tan(alpha - phi), rel=1e-3)
    assert not m["jammed"]
    # on the shank, friction adds mu times the contact force axially
    assert m["insertion_force"][-1] == pytest.approx(0.2 * m["final_contact_force"], rel=1e-3)


def test_3d_lateral_stiffness_is_cantilever_theory():
    """Frictionless: the force on the shank over the interference (0.15 mm = 3 % of L) against
    Timoshenko's tip stiffness (3EI/L^3 with shear) of a beam of the spring's width b = 1 mm,
    within 0.5 % (measured: +0.1 %; 3EI/L^3 alone is 0.3 % stiffer)."""
    m = simulate(["effects=[]", "steps.0.motion.y=-0.34", "steps.0.increments=3", "steps.1.motion.y=-0.34",
                  "steps.1.increments=1"])
    scene = load_scene(SCENE)
    spring, material = scene["spring"], scene["materials"]["spring"]
    k = reference.timoshenko_stiffness(material["E"], material["nu"], spring["thickness"], spring["length"],
                                       spring["width"])
    assert m["final_contact_force"] / spring["interference"] == pytest.approx(k, rel=5e-3)
    assert m["stiffness_3EI_L3"] == pytest.approx(material["E"] * spring["width"] * spring["thickness"] ** 3
                                                  / (4 * spring["length"] ** 3))
    assert m["insertion_force"][-1] == pytest.approx(0.0, abs=1e-6)
