"""Snap fit in 3-D, coarse: scenes/snap_fit_3d.toml, the 2-D scene's spring swept across
its 1 mm width (quadratic tetrahedra, 2 across the thickness, 4 layers across the width) and a
blade pin whose flat-taper section is the same in every plane z = const. The checks of the 2-D
scene hold with forces in N over the whole width: the flat taper's force ratio equals the statics
of a sliding interface (alpha from the insertion axis, phi = atan(mu)), and the spring's lateral
stiffness lies between beam theory with the spring's width b and a wide plate strip's."""
import math
from pathlib import Path

import pytest

from femcontact.families import load_scene
from femcontact.references import snap_fit as reference

SCENE = Path(__file__).parents[2] / "scenes" / "snap_fit_3d.toml"
SHORT = ["steps.0.motion.y=-0.34", "steps.0.increments=10"]  # 0.05 gap, 0.26 on the taper, 0.03 on the shank


def run(overrides: list[str]):
    """The scene with `overrides`, run to its end."""
    from femcontact.solver.stepping import Simulation

    simulation = Simulation(load_scene(SCENE, overrides))
    simulation.run()
    return simulation


def simulate(overrides: list[str]) -> dict:
    from femcontact.families.snap_fit.metrics import snap_fit_metrics

    return snap_fit_metrics(run(overrides))


def test_3d_flat_taper_force_ratio_equals_statics():
    """30 deg taper, mu 0.2, in and back out over the taper (withdrawal to 0.05 mm past first touch)."""
    m = simulate(SHORT + ["steps.1.motion.y=-0.1", "steps.1.increments=6"])
    alpha, phi = math.radians(30.0), math.atan(0.2)
    assert m["insertion_force_ratio"] == pytest.approx(math.tan(alpha + phi), rel=1e-3)
    assert m["withdrawal_force_ratio"] == pytest.approx(math.tan(alpha - phi), rel=1e-3)
    assert not m["jammed"]
    # on the shank, friction adds mu times the contact force axially
    assert m["insertion_force"][-1] == pytest.approx(0.2 * m["final_contact_force"], rel=1e-3)


def test_3d_lateral_stiffness_lies_between_beam_and_plate_strip_with_the_apex_on_the_shank():
    """Frictionless: the force on the shank over the interference (0.15 mm = 3 % of L) lies between
    Timoshenko's tip stiffness of a beam of the spring's width b = 1 mm (3EI/L^3 with shear: plane
    stress, which the 2-D plane-stress scene reproduces to 0.03 %) and the same over 1 - nu^2 (an
    infinitely wide strip, plane strain, +9.9 %): a strip 3.3 thicknesses wide whose clamped root
    holds its Poisson contraction (measured +1.5 % on this mesh, +1.4 % at resolution 2). The apex,
    a sharp edge of the spring, stays on the shank to the penalty's overclosure (measured 1e-4 of
    the interference): the contact is integrated at the facets' nodes, where Gauss points inside
    the facets let it sink by 1.7 % of the interference on this mesh."""
    import numpy as np

    from femcontact.families.snap_fit.metrics import snap_fit_metrics
    from geometry.snap_fit import layout

    simulation = run(["effects=[]", "steps.0.motion.y=-0.34", "steps.0.increments=3", "steps.1.motion.y=-0.34",
                      "steps.1.increments=1"])
    scene, m = simulation.problem.scene, snap_fit_metrics(simulation)
    spring, material = scene["spring"], scene["materials"]["spring"]
    k = reference.timoshenko_stiffness(material["E"], material["nu"], spring["thickness"], spring["length"],
                                       spring["width"])
    stiffness = m["final_contact_force"] / spring["interference"]
    assert k < stiffness < k / (1 - material["nu"] ** 2)
    assert m["stiffness_3EI_L3"] == pytest.approx(material["E"] * spring["width"] * spring["thickness"] ** 3
                                                  / (4 * spring["length"] ** 3))
    assert m["insertion_force"][-1] == pytest.approx(0.0, abs=1e-6)

    newton = simulation.newton  # the owned nodes' coordinates and displacements
    x, u = newton.coordinates, simulation.problem.u.x.array[: newton.n_owned * 3].reshape(-1, 3)
    apex = np.all(np.isclose(x[:, :2], layout(scene).apex, rtol=0, atol=1e-9), axis=1)
    sunk = scene["peg"]["width"] / 2 - (x[apex, 0] + u[apex, 0])
    assert apex.sum() >= 2 and sunk.max() < 1e-3 * spring["interference"]
