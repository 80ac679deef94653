"""The RCC device: the reference tables, the reverse problem, the compliance centre, the CLI."""
import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from femcontact.families.rcc import device as rcc
from femcontact.cli import main
from femcontact.errors import InputError
from femcontact.families import resolve_scene
from femcontact.families.rcc.case import run_case
from femcontact.physics.rotation import rotation_numpy as rotation_zyx

DATA = Path(__file__).resolve().parents[1] / "data" / "rcc_validation.csv"
ROWS = list(csv.DictReader(line for line in open(DATA) if not line.startswith("#")))
DEVICE = rcc.Rcc(50, 50, 70, 200)


def _half_unit(value: float) -> float:
    """Half a unit in the last of the table's five significant digits."""
    return 0.5 * 10.0 ** (math.floor(math.log10(abs(value))) - 4)


@pytest.mark.parametrize("row", ROWS, ids=[f"{r['table']}-{r['dof']}={r['value']}" for r in ROWS])
def test_reference_table_row(row):
    """Approximation columns to the table's 5 digits; exact columns within 0.05 % or 2e-3;
    the table's error_pct (computed from its rounded columns) within that rounding."""
    device = rcc.Rcc(float(row["b"]), float(row["L_model"]), float(row["theta_L"]), float(row["k"]))
    dof = rcc.DOFS.index(row["dof"])
    motion = np.zeros(6)
    motion[dof] = float(row["value"])
    about_z = float(row["L_true"]) - float(row["L_model"])
    approx = rcc.wrench(device, motion, model="approx")
    exact = rcc.wrench(device, motion, about_z)
    for i, name in enumerate(rcc.WRENCH):
        table_approx, table_exact = float(row["approx_" + name]), float(row["num_" + name])
        if table_approx == 0.0:
            assert approx[i] == 0.0
        else:
            assert abs(approx[i] - table_approx) <= _half_unit(table_approx) * (1 + 1e-9)
        assert exact[i] == pytest.approx(table_exact, rel=5e-4, abs=2e-3)
    table_approx, table_exact = float(row["approx_" + rcc.WRENCH[dof]]), float(row["num_" + rcc.WRENCH[dof]])
    rounding = 100 * (_half_unit(table_approx) + _half_unit(table_exact)) / abs(table_approx) + 5e-5
    error_pct = 100 * (exact[dof] - approx[dof]) / approx[dof]
    assert error_pct == pytest.approx(float(row["error_pct"]), abs=rounding)


@pytest.mark.parametrize("geometry", [(50, 50, 70, 200, 0), (43.3, 25, 60, 30, 0), (50, 20, 55, 100, 8.0)])
def test_linear_truss_stiffness_is_the_reference_formula(geometry):
    """S = a^T k a of the truss equals the closed form for any b, L, theta_L (and T: the
    raised base keeps the link lines)."""
    device = rcc.Rcc(*geometry)
    linear = np.column_stack([rcc.wrench(device, column, model="linear") for column in np.eye(6)])
    formula = rcc.formula_stiffness(device)
    assert np.allclose(linear, formula, rtol=0, atol=1e-12 * formula.max())


def test_raised_base_separates_the_corner_joints_and_shortens_links():
    device = rcc.Rcc(50, 50, 70, 200, offset_t=5.0)
    base, wrist = device.links()
    assert np.allclose(base[:, 2], -device.height + 5.0)
    assert np.linalg.norm(base[0] - base[5]) == pytest.approx(5.0 / math.tan(device.theta))
    lengths = np.linalg.norm(wrist - base, axis=1)
    assert np.allclose(lengths, device.raised_link_length)
    assert device.raised_link_length == pytest.approx(device.link_length - 5.0 / math.sin(device.theta))


def test_reverse_problem_round_trip_and_small_load_limit():
    """displacement() inverts wrench(): the tip force moves with the tip, so the wrench about
    the fixed point carries the extra moment t x F. Small loads: exact -> C W."""
    load = np.array([100.0, -50.0, 200.0, 3000.0, -2000.0, 1000.0])
    for about_z in (0.0, 3.0):
        motion = rcc.displacement(DEVICE, load, about_z)
        held = rcc.wrench(DEVICE, motion, about_z)
        expected = np.r_[load[:3], load[3:] + np.cross(motion[:3], load[:3])]
        assert np.allclose(held, expected, rtol=0, atol=1e-9 * np.abs(load).max())
    small = load * 1e-6
    approx = rcc.displacement(DEVICE, small, model="approx")
    assert np.allclose(approx, np.linalg.solve(rcc.formula_stiffness(DEVICE), small), rtol=1e-14)
    assert np.allclose(rcc.displacement(DEVICE, small), approx, rtol=0, atol=1e-5 * np.abs(approx).max())


def test_motion_about_another_point_is_the_same_motion_seen_from_the_tip():
    """A motion (t, R) about p = (0, 0, DZ) is the motion (t + (I - R) p, R) about the tip;
    its wrench about p is the tip wrench with M_p = M_O - p x F. The approximation about p
    is A^T S A (a translation-tilt coupling -S_xx DZ appears)."""
    motion, dz = np.array([0.3, -0.2, 0.1, 0.02, -0.01, 0.03]), 3.0
    p = np.array([0, 0, dz])
    rotation = rotation_zyx(motion[3:])
    at_tip = rcc.wrench(DEVICE, np.r_[motion[:3] + p - rotation @ p, motion[3:]])
    about_p = rcc.wrench(DEVICE, motion, dz)
    assert np.allclose(about_p, np.r_[at_tip[:3], at_tip[3:] - np.cross(p, at_tip[:3])], atol=1e-9)
    s = rcc.approx_stiffness(DEVICE, dz)
    assert s[0, 4] == pytest.approx(-rcc.formula_stiffness(DEVICE)[0, 0] * dz)  # tip lags by -DZ ry
    tiny = motion * 1e-6
    assert np.allclose(rcc.wrench(DEVICE, tiny, dz), s @ tiny, rtol=0, atol=1e-5 * np.abs(s @ tiny).max())


@pytest.mark.parametrize("geometry", [(50, 50, 70, 200, 0), (43.3, 25, 60, 30, 0), (50, 20, 55, 100, 8.0)])
def test_compliance_centre_is_at_the_tip_in_the_small_motion_limit(geometry):
    device = rcc.Rcc(*geometry)
    assert abs(rcc.compliance_centre(device)["z"]) < 1e-9
    assert abs(rcc.compliance_centre(device, load=[0, 0, -1e-6, 0, 0, 0])["z"]) < 1e-6
    assert abs(rcc.compliance_centre(device, motion=[1e-6, 0, 0, 0, 0, 0])["z"]) < 1e-6
    # the truss's own small-motion stiffness at the tip (central differences of the exact
    # wrench) is the decoupled design formula: off-diagonal terms vanish, the diagonal matches
    h = 1e-6
    S = np.column_stack([(rcc.wrench(device, h * e) - rcc.wrench(device, -h * e)) / (2 * h) for e in np.eye(6)])
    design = rcc.formula_stiffness(device)
    scale = np.sqrt(np.outer(np.diag(design), np.diag(design)))
    assert np.abs((S - design) / scale).max() < 1e-6


def test_compliance_centre_under_axial_load_decouples_a_lateral_push():
    """Under an axial preload the centre leaves the tip; a small lateral force through the
    computed centre translates the peg without tilting it (much less than at the tip)."""
    preload = np.array([0, 0, -100.0, 0, 0, 0])
    centre = rcc.compliance_centre(DEVICE, load=preload)
    assert centre["z"] > 0.1 and centre["coupling"] < 1e-12
    push = np.array([0.01, 0, 0, 0, 0, 0])

    def tilt(about_z):
        return (rcc.displacement(DEVICE, preload + push, about_z)
                - rcc.displacement(DEVICE, preload, about_z))[4]

    assert abs(tilt(centre["z"])) < 1e-3 * abs(tilt(0.0))
    # twice the preload moves the centre about twice as far (geometric stiffness ~ link force)
    assert rcc.compliance_centre(DEVICE, load=2 * preload)["z"] == pytest.approx(2 * centre["z"], rel=0.05)


@pytest.mark.parametrize("kwargs, message", [
    (dict(theta_l=90), "theta_L"), (dict(theta_l=0), "theta_L"), (dict(k=0), "k ="),
    (dict(b=-1), "b ="), (dict(peg_length=60, theta_l=50), "h = H - L"), (dict(offset_t=90), "offset T"),
])
def test_bad_geometry_is_an_input_error(kwargs, message):
    values = dict(b=50, peg_length=50, theta_l=70, k=200) | kwargs
    with pytest.raises(InputError, match=message):
        rcc.Rcc(**values)


GEOMETRY = ["--b", "50", "--peg-length", "50", "--theta-l", "70", "--k", "200"]


def _cli(capsys, *args):
    code = main(["rcc", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_wrench_json_contract(capsys):
    code, out, _ = _cli(capsys, "wrench", *GEOMETRY, "--move", "rx=0.05", "--json")
    assert code == 0
    result = json.loads(out)
    assert list(result) == ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    assert result["Mx"] == pytest.approx(22687.0, abs=0.5)  # table A-12
    assert result["Fz"] == pytest.approx(113.14, abs=0.01)
    code, out, _ = _cli(capsys, "wrench", *GEOMETRY, "--move", "rx=0.05", "--move", "x=0.1",
                        "--about-z", "3", "--model", "approx", "--json")
    expected = rcc.approx_stiffness(DEVICE, 3.0) @ [0.1, 0, 0, 0.05, 0, 0]
    assert list(json.loads(out).values()) == pytest.approx(expected.tolist())


def test_cli_displace_centre_and_table_output(capsys):
    code, out, _ = _cli(capsys, "displace", *GEOMETRY, "--load", "Fx=100", "--load", "Mz=500",
                        "--model", "approx", "--json")
    result = json.loads(out)
    assert code == 0 and list(result) == list(rcc.DOFS)
    assert result["x"] == pytest.approx(100 / rcc.formula_stiffness(DEVICE)[0, 0])
    assert result["rz"] == pytest.approx(500 / rcc.formula_stiffness(DEVICE)[5, 5])
    code, out, _ = _cli(capsys, "centre", *GEOMETRY, "--json")
    assert code == 0 and abs(json.loads(out)["z"]) < 1e-9
    code, out, _ = _cli(capsys, "centre", *GEOMETRY, "--offset-t", "5", "--load", "Fz=-100")
    assert code == 0 and out.split()[0] == "z" and float(out.split()[1]) > 0.1


@pytest.mark.parametrize("args", [
    ["wrench", "--b", "50", "--peg-length", "50", "--theta-l", "95", "--k", "200", "--move", "x=1"],
    ["wrench", "--b", "50", "--peg-length", "50", "--theta-l", "70", "--k", "-2", "--move", "x=1"],
    ["wrench", "--b", "0", "--peg-length", "50", "--theta-l", "70", "--k", "200", "--move", "x=1"],
    ["wrench", "--b", "50", "--peg-length", "200", "--theta-l", "70", "--k", "200", "--move", "x=1"],
    ["wrench", *GEOMETRY, "--move", "rx"],
    ["wrench", *GEOMETRY, "--move", "rx=abc"],
    ["wrench", *GEOMETRY, "--move", "w=1"],
    ["wrench", *GEOMETRY, "--move", "x=1", "--move", "x=2"],
    ["wrench", *GEOMETRY, "--move", "x=nan"],
    ["displace", *GEOMETRY, "--load", "Fq=1"],
    ["centre", *GEOMETRY, "--load", "Fz=-1", "--move", "x=1"],
])
def test_cli_bad_input_exits_2_with_a_message(capsys, args):
    code, out, err = _cli(capsys, *args)
    assert code == 2 and out == "" and "error:" in err


def test_run_case_metrics_are_flat_and_match_the_tables():
    scene = resolve_scene({"kind": "rcc", "rcc": {"theta_l": 70, "peg_length": 50},
                     "motion": {"translation": 1.0, "rotation": 0.05}})
    result = run_case(scene)
    metrics = result["metrics"]
    assert all(isinstance(v, (float, int, bool, str)) for v in metrics.values())
    assert metrics["error_rx"] == pytest.approx(0.027678, abs=5e-5)  # table A-12, 0.05 rad
    assert metrics["Mx_rx"] == pytest.approx(22687.0, abs=0.5)
    assert metrics["worst_dof"] == "rx"
    assert metrics["max_rel_error"] == max(abs(metrics[f"error_{d}"]) for d in rcc.DOFS)
    assert abs(metrics["centre_z_unloaded"]) < 1e-9
    with pytest.raises(InputError, match="theta_l"):
        resolve_scene({"kind": "rcc", "rcc": {"theta_l": 90}})
