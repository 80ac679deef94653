"""The 3-D convergence report (benchmarks/convergence_3d.py, `make convergence_3d`) on made-up
rungs: a quantity f(h) = f0 + C h^2 on meshes refined by sqrt(2) is extrapolated to f0 with
order 2, and the finest rung's error is |f(h_finest) - f0| / f0; a failed rung is left out."""
import math
from pathlib import Path

import pytest

from benchmarks import convergence_3d

WEDGING = convergence_3d.LADDERS["wedging_3d"]


def rows(f0: float = 70.0, c: float = -5.0, order: float = 2.0) -> list[dict]:
    out = []
    for resolution in convergence_3d.RESOLUTIONS:
        h = 1.0 / resolution
        row = {"resolution": resolution, "status": "ok", "dofs": int(17000 * resolution ** 2.7),
               "newton_iterations": 90, "wall_time": 10.0}
        row.update({key: f0 + c * h ** order for key in WEDGING.quantities})
        out.append(row)
    return out


def test_richardson_recovers_the_limit_and_the_order():
    table = convergence_3d.extrapolation("wedging_3d", rows())
    assert len(table) == len(WEDGING.quantities)
    for entry in table:
        assert entry["limit"] == pytest.approx(70.0, rel=1e-12)
        assert entry["order"] == pytest.approx(2.0, rel=1e-9)
        assert entry["error"] == pytest.approx(5.0 / 8.0 / 70.0, rel=1e-9)  # h_finest^2 = 1/8
        assert entry["spread"] == pytest.approx(5.0 * (1 / 2 - 1 / 8) / 69.375, rel=1e-9)  # h^2 = 1/2 ... 1/8
    assert "| contact force at A after release (N) | 69.375 | 70 | 2.00 | 0.89% | yes | 2.70% |" \
        in convergence_3d.report("wedging_3d", rows())


def test_rungs_that_oscillate_have_no_order_and_three_times_their_spread_as_error():
    """Eca and Hoekstra's uncertainty for oscillatory convergence, 3 x the range of the three
    finest: 3 x (68.28 - 68.00) / 68.28 = 1.23 %."""
    data = rows()
    for row, value in zip(data, (69.33, 68.12, 68.00, 68.28)):  # measured, docs/wedging_3d.md
        row["residual_force_A"] = value
    entry = convergence_3d.extrapolation("wedging_3d", data)[0]
    assert math.isnan(entry["order"]) and entry["how"] == "range"
    assert entry["spread"] == pytest.approx(0.28 / 68.28, rel=1e-9)
    assert entry["error"] == pytest.approx(3 * 0.28 / 68.28, rel=1e-9)
    assert "| 1.23% (3 x spread: not monotone) | no | 0.41% |" in convergence_3d.report("wedging_3d", data)


def test_the_measured_wall_normal_tilts_carry_an_error_below_the_target():
    """The linear wall-normal ladder's loaded tilts (docs/wedging_3d.md) alternate: 1.28106,
    1.28070, 1.28431 deg; 3 x 0.00361 / 1.28431 = 0.84 %, within the 1 % a published 3-D number
    may carry. A range three times as wide would not be."""
    from femcontact.references.richardson import range_error

    assert range_error([1.28106, 1.28070, 1.28431]) == pytest.approx(3 * 0.00361 / 1.28431, rel=1e-9)
    assert range_error([1.28106, 1.28070, 1.28431]) <= convergence_3d.TARGET
    assert range_error([1.28106, 1.27348, 1.28431]) > convergence_3d.TARGET
    assert range_error([1.0, -1.0, 0.0]) is None  # no relative error of a zero


def test_a_failed_rung_is_left_out_of_the_extrapolation():
    data = rows()
    data[-1].update(status="failed", **{key: None for key in WEDGING.quantities})
    table = convergence_3d.extrapolation("wedging_3d", data)  # the three ok rungs: still f0 exactly
    assert table[0]["limit"] == pytest.approx(70.0, rel=1e-12)
    assert "failed" in convergence_3d.report("wedging_3d", data)


def test_three_finest_rungs_not_refined_by_one_ratio_are_refused():
    data = rows()
    data[-1]["resolution"] = 3.5  # 2 -> 2.83 -> 3.5: ratios 1.41 and 1.24
    with pytest.raises(convergence_3d.InputError, match="refined by one ratio"):
        convergence_3d.extrapolation("wedging_3d", data)


def test_an_order_above_the_discretisations_is_estimated_at_its_order_with_a_factor_of_safety():
    """f = 70 - 5 h^3 with P1 (order 2 at most): the error is 3 |f3 - f2| / (sqrt(2)^2 - 1) / |f3|,
    3 x 5 (2^-3 - 2^-4.5) / 69.779 = 1.74 %, five times the true 0.32 %."""
    data = rows(order=3.0)
    table = convergence_3d.extrapolation("wedging_3d", data)
    f2, f3 = 70.0 - 5.0 / 8.0, 70.0 - 5.0 * 2 ** -4.5
    for entry in table:
        assert entry["order"] == pytest.approx(3.0, rel=1e-9) and entry["how"] == "capped"
        assert entry["error"] == pytest.approx(3.0 * (f3 - f2) / (2.0 - 1.0) / f3, rel=1e-9)
        assert entry["error"] > 5 * abs(f3 - 70.0) / 70.0
    assert "| 1.74% (order 2, x3) | no |" in convergence_3d.report("wedging_3d", data)


def test_the_measured_p2_wedging_force_gets_an_error_estimate():
    """The P2 exact-surface ladder's loaded force at A (docs/wedging_3d.md): 78.6442, 78.5145,
    78.4875 N line up at order 4.5, above P2's 3: 3 x 0.0270 / (2^1.5 - 1) / 78.4875 = 0.056 %."""
    from femcontact.references.richardson import finest_error

    error, order = finest_error([78.6442, 78.5145, 78.4875], 2 ** 0.5, 3.0)
    assert order == 3.0 and error == pytest.approx(3 * 0.0270 / (2 ** 1.5 - 1) / 78.4875, rel=1e-9)


def test_rungs_that_alternate_get_no_order_even_when_their_steps_shrink():
    """Steps of opposite sign (here -0.78 then +0.39: |ratio| 1/2) are no convergence to
    extrapolate, whatever their sizes: the finest value, no order, and 3 x the spread as error."""
    from femcontact.references.richardson import richardson

    limit, order = richardson([66.44, 65.66, 66.05], 2 ** 0.5)
    assert limit == 66.05 and math.isnan(order)
    data = rows()
    for row, value in zip(data, (66.44, 65.66, 67.34, 66.50)):  # P2 on the exact surface, docs/wedging_3d.md
        row["residual_force_A"] = value
    entry = convergence_3d.extrapolation("wedging_3d", data)[0]
    assert entry["how"] == "range" and entry["error"] == pytest.approx(3 * (67.34 - 65.66) / 66.50, rel=1e-9)
    assert "| 7.58% (3 x spread: not monotone) | no | 2.53% |" in convergence_3d.report("wedging_3d", data)


def test_a_coarser_rung_that_moves_the_other_way_withholds_the_estimate():
    """The three finest tilts of the curved insertion ladder (-1.70681, -1.67175, -1.66575 deg)
    line up at order 5.1, but the rung before moved the other way (-1.70654): no Richardson
    estimate (the report gives 3 x the spread instead). The
    P2 wedging force, whose four rungs each move less the same way, keeps its 0.06 %."""
    from femcontact.references.richardson import finest_error

    assert finest_error([-1.70654, -1.70681, -1.67175, -1.66575], 2 ** 0.5, 3.0)[0] is None
    assert finest_error([-1.70681, -1.67175, -1.66575], 2 ** 0.5, 3.0)[0] is not None
    error, _ = finest_error([79.0282, 78.6442, 78.5145, 78.4875], 2 ** 0.5, 3.0)
    assert error == pytest.approx(3 * 0.0270 / (2 ** 1.5 - 1) / 78.4875, rel=1e-9)
    assert finest_error([1.0, 1.1, 1.4, 1.5], 2 ** 0.5, 3.0)[0] is None  # steps 0.1, 0.3, 0.1: one grows


def test_the_3d_dislodging_thresholds_carry_three_times_the_spread_of_their_finest_meshes():
    """The 3-D pull-out of `make dislodging_methods_3d` (docs/dislodging_methods.md) on meshes 0.5,
    1, 1.5 and 2: the three finest, 10.814, 10.690, 10.481 N, move one way by growing steps, so
    the finest carries 3 x 0.333 / 10.481 = 9.5 %; the coarser mesh is left out."""
    from femcontact.families.dislodging.methods_report import errors_3d

    pulls = [{"method": "pull along the axis", "mesh.resolution": r, "threshold_force_N": p, "degree_of_wedging": g}
             for r, p, g in ((2.0, 10.481, 0.3599), (0.5, 12.181, 0.3961), (1.0, 10.814, 0.3627),
                             (1.5, 10.690, 0.3614))]
    twists = [{"method": "twist across the axis", "mesh.resolution": r, "threshold_moment_Nmm": m}
              for r, m in ((1.0, 214.3), (1.5, 206.2))]  # two meshes: no estimate
    rows = errors_3d(pulls + twists)
    assert [(r["quantity"], r["mesh.resolution"], r["estimated_error"]) for r in rows] == [
        ("threshold_force_N", "1, 1.5, 2", f"{3 * (10.814 - 10.481) / 10.481:.1%}"),
        ("degree_of_wedging", "1, 1.5, 2", f"{3 * (0.3627 - 0.3599) / 0.3599:.1%}")]
    assert rows[0]["estimated_error"] == "9.5%"


def test_the_crossing_ladder_refines_the_study_s_tilted_rcc_case():
    """The ladder insertion_3d_rcc_p2_wall runs the second case of studies/insertion_3d.toml, key
    by key, on curved quadratic elements along the wall's normal."""
    import tomllib

    study = tomllib.loads((Path(__file__).parents[2] / "studies" / "insertion_3d.toml").read_text())
    settings = convergence_3d.LADDERS["insertion_3d_rcc_p2_wall"].settings
    parsed = {key: tomllib.loads(f"v = {value}")["v"] for key, value in settings.items()}
    assert {key: parsed[key] for key in study["sweep"]["cases"][1]} == study["sweep"]["cases"][1]
    assert (parsed["mesh.degree"], parsed["mesh.geometry_order"], parsed["contact.normal"]) == (2, 2, "wall")
