"""3-D wedging: a rigid cylindrical peg wedged in a round hole by a couple and released.

One coarse case (scenes/wedging_3d.toml at resolution 0.5, ~3k dofs, ~25 s on one rank):
after the couple is removed the peg must stay wedged: both contact zones keep a resultant
(well above the 2 % floor of femcontact.wedging), the released state needs no contact
stabilisation, the two resultants balance (no external load) and lie on the line through
the two contact centres (a wedged peg is a two-force body). The same with the peg's rims
rounded (`peg.corner_radius` = 1 mm, ~10 s): wedged alike, and contact B found on the rim's
torus where the placement puts it, which the sharp rim misses on this mesh; and with a 1 mm x
45 deg tip chamfer (`peg.chamfer_width`, a cone): wedged alike. See docs/wedging_3d.md.
"""
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene
from femcontact.solver.stepping import Simulation

SCENE = Path(__file__).parents[2] / "scenes" / "wedging_3d.toml"


def zone(row: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(resultant force on the block, force centre) of contact zone `name` (N, mm)."""
    force = np.array([row[f"contact_{name}_F{a}"] for a in "xyz"])
    centre = np.array([row[f"contact_{name}_{a}"] for a in "xyz"])
    return force, centre


def run(*overrides: str) -> Simulation:
    simulation = Simulation(load_scene(SCENE, ["mesh.resolution=0.5", *overrides]))
    simulation.run()
    return simulation


@pytest.fixture(scope="module")
def released():
    return run()


@pytest.fixture(scope="module")
def rounded():
    return run("peg.corner_radius=1.0")


@pytest.fixture(scope="module")
def chamfered():
    return run("peg.chamfer_width=1.0")


def test_couple_increases_the_tilt(released):
    rows = released.step_end_rows()
    assert rows["load"]["tilt_deg"] > np.degrees(released.problem.model.rigid["tilt"])


@pytest.mark.parametrize("case", ["released", "rounded", "chamfered"])
def test_released_peg_stays_wedged(case, request):
    row = request.getfixturevalue(case).step_end_rows()["release"]
    moment = 1000.0
    arm = 40.0  # ~ l_2P: the force of the couple is ~25 N
    f_a, c_a = zone(row, "A")
    f_b, c_b = zone(row, "B")
    assert np.linalg.norm(f_a) > 0.02 * moment / arm
    assert row["stabilization_force"] == 0.0
    assert np.linalg.norm(f_a + f_b) < 1e-3 * np.linalg.norm(f_a)
    line = c_b - c_a
    for force in (f_a, f_b):
        cosine = abs(force @ line) / (np.linalg.norm(force) * np.linalg.norm(line))
        assert np.degrees(np.arccos(min(cosine, 1.0))) < 1.0


def test_rounded_rim_touches_the_wall_where_placed(rounded):
    """Contact B's force centre lies within 0.1 mm (a tenth of the contact elements, h_c = 1 mm)
    of the rounded rim's tangent point on the wall, as placed (z = -2.862 mm; measured 0.027 mm
    above it). The sharp rim's centre lies 0.39 mm above its edge on this mesh (docs/wedging_3d.md)."""
    placed = rounded.problem.model.points["contact_B"]
    _, centre = zone(rounded.step_end_rows()["release"], "B")
    assert placed[2] == pytest.approx(-2.8618, abs=1e-4)
    assert abs(centre[2] - placed[2]) < 0.1
