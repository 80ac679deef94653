"""The 3-D convergence report (benchmarks/convergence_3d.py, `make convergence_3d`) on made-up
rungs: a quantity f(h) = f0 + C h^2 on meshes refined by sqrt(2) is extrapolated to f0 with
order 2, and the finest rung's error is |f(h_finest) - f0| / f0; a failed rung is left out."""
import math

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


def test_rungs_that_oscillate_have_no_order_but_a_spread():
    data = rows()
    for row, value in zip(data, (69.33, 68.12, 68.00, 68.28)):  # measured, docs/wedging_3d.md
        row["residual_force_A"] = value
    entry = convergence_3d.extrapolation("wedging_3d", data)[0]
    assert entry["error"] is None
    assert entry["spread"] == pytest.approx(0.28 / 68.28, rel=1e-9)
    assert "| not converging | no | 0.41% |" in convergence_3d.report("wedging_3d", data)


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
        assert entry["order"] == pytest.approx(3.0, rel=1e-9) and entry["capped"]
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
    extrapolate, whatever their sizes: the finest value, no order, no error estimate."""
    from femcontact.references.richardson import richardson

    limit, order = richardson([66.44, 65.66, 66.05], 2 ** 0.5)
    assert limit == 66.05 and math.isnan(order)
    data = rows()
    for row, value in zip(data, (66.44, 65.66, 67.34, 66.50)):  # P2 on the exact surface, docs/wedging_3d.md
        row["residual_force_A"] = value
    entry = convergence_3d.extrapolation("wedging_3d", data)[0]
    assert entry["error"] is None
    assert "| not converging | no | 2.53% |" in convergence_3d.report("wedging_3d", data)


def test_a_coarser_rung_that_moves_the_other_way_withholds_the_estimate():
    """The three finest tilts of the curved insertion ladder (-1.70681, -1.67175, -1.66575 deg)
    line up at order 5.1, but the rung before moved the other way (-1.70654): no estimate. The
    P2 wedging force, whose four rungs each move less the same way, keeps its 0.06 %."""
    from femcontact.references.richardson import finest_error

    assert finest_error([-1.70654, -1.70681, -1.67175, -1.66575], 2 ** 0.5, 3.0)[0] is None
    assert finest_error([-1.70681, -1.67175, -1.66575], 2 ** 0.5, 3.0)[0] is not None
    error, _ = finest_error([79.0282, 78.6442, 78.5145, 78.4875], 2 ** 0.5, 3.0)
    assert error == pytest.approx(3 * 0.0270 / (2 ** 1.5 - 1) / 78.4875, rel=1e-9)
    assert finest_error([1.0, 1.1, 1.4, 1.5], 2 ** 0.5, 3.0)[0] is None  # steps 0.1, 0.3, 0.1: one grows
