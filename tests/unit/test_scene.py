"""Scene files: validation messages name the key, the value and what is allowed; overrides
go through the same validation; the closed forms match the reference's Table 3-1."""
import json
import math
import re

import pytest

from femcontact.references import peg_in_hole as analytic
from femcontact.cli import main
from femcontact.errors import InputError
from femcontact.config.scene import case_id
from femcontact.families import load_scene, resolve_scene

BASE = {"dim": 2, "geometry": "peg_in_hole", "peg": {"width": 40, "length": 10, "insertion_depth": 5},
        "hole": {"width": 40.1}, "steps": [{"name": "load", "force": [-5.0, 1.0]}]}


@pytest.mark.parametrize("change, message", [
    ({"peg.widht": 40}, "peg.widht: unknown key"),
    ({"contact.mu": "high"}, "contact.mu = 'high': wrong type, expected a number"),
    ({"contact.mu": -0.1}, "contact.mu = -0.1: out of range, expected a number >= 0.0"),
    ({"effects": ["friction", "magnetism"]}, "effects = ['friction', 'magnetism']: not allowed"),
    ({"effects": ["plane_strain", "plane_stress"]}, "exclude each other"),
    ({"materials.hole.nu": 0.5}, "materials.hole.nu = 0.5: out of range"),
    ({"steps.0.force": [1.0]}, "steps[0].force = [1.0]: expected 2 components"),
    ({"hole.width": 39.0}, "hole"),
    ({"peg.insertion_depth": 11.0}, "insertion_depth"),
    ({"dim": 4}, "dim = 4: not allowed, expected one of 2, 3"),
])
def test_bad_scene_files_give_one_clear_message(tmp_path, change, message):
    from femcontact.config.schema import set_key
    from femcontact.study.study_file import to_toml

    data = json.loads(json.dumps(BASE))
    for key, value in change.items():
        set_key(data, key, value)
    path = tmp_path / "bad.toml"
    path.write_text(to_toml(data))
    with pytest.raises(InputError, match=re.escape(message)):
        load_scene(path)


def test_override_goes_through_validation():
    with pytest.raises(InputError, match="peg.insertion_depth = -1: out of range"):
        resolve_scene(BASE, ["peg.insertion_depth=-1"])
    assert resolve_scene(BASE, ["peg.insertion_depth=6"])["peg"]["insertion_depth"] == 6.0


def test_cli_reports_bad_input_with_exit_code_2(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text("[contact]\nmethod = 'lagrange'\n")
    assert main(["run", str(scene)]) == 2
    assert "contact.method = 'lagrange'" in capsys.readouterr().err


def test_case_id_ignores_order_and_formatting():
    reordered = {"steps": BASE["steps"], "hole": {"width": 40.10}, "peg": {"length": 10.0, "insertion_depth": 5,
                                                                           "width": 40}, "geometry": "peg_in_hole",
                 "dim": 2}
    assert case_id(resolve_scene(BASE)) == case_id(resolve_scene(reordered))
    assert case_id(resolve_scene(BASE)) != case_id(resolve_scene(BASE, ["peg.insertion_depth=5.0001"]))


@pytest.mark.parametrize("l_d, tilt_deg", [(4.0, 1.6784), (5.0, 1.2560), (6.0, 1.0148)])
def test_two_point_tilt_matches_reference_table(l_d, tilt_deg):
    """Table 3-1 lists 4 decimals; the formula agrees to 2e-4 deg (the table rounds)."""
    assert math.degrees(analytic.tilt_two_point(40.0, 40.1, l_d)) == pytest.approx(tilt_deg, abs=2e-4)


def test_wedging_bounds():
    assert analytic.l_crit(40.0, 40.1) == pytest.approx(2.8302, abs=1e-4)
    assert analytic.l_max(40.0, 0.2) == 8.0
    assert analytic.can_wedge(40.0, 40.1, 0.2, 5.0) and not analytic.can_wedge(40.0, 40.1, 0.2, 10.0)
    assert math.degrees(analytic.tilt_crit(40.0, 40.1)) == pytest.approx(math.degrees(
        analytic.tilt_two_point(40.0, 40.1, analytic.l_crit(40.0, 40.1))), abs=1e-9)


def test_solver_options_carry_every_solver_key_of_the_scene():
    """The solver reads no scene: `SolverOptions` hold every [solver] key, as set, and cannot change."""
    import dataclasses

    from femcontact.config.scene import SOLVER
    from femcontact.config.solver import SCENE_KEYS, solver_options

    scene = resolve_scene(BASE, ["solver.rtol=1e-7", "solver.curved_step=true", "solver.petsc_options={pc_type='lu'}"])
    options = solver_options(scene)
    assert set(SCENE_KEYS) == set(SOLVER)
    assert {key: getattr(options, key) for key in SOLVER} == scene["solver"]
    assert options.rtol == 1e-7 and options.curved_step is True and options.petsc_options == {"pc_type": "lu"}
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.rtol = 1.0
    with pytest.raises(TypeError):
        options.petsc_options["pc_type"] = "gamg"
