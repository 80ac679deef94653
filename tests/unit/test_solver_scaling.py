"""The solver-scaling benchmark (benchmarks/solver_scaling.py, `make bench_solvers`) on a coarse
mesh: both linear solvers take the same Newton iterations to the same residual (the iterative
one to its tolerance, 1e-6 of the right-hand side), and the fitted exponent is the slope of
log time against log unknowns; the parts of a later iteration lie within it; a rung's memory
is predicted from the last smaller one."""
import math

import pytest

from benchmarks import solver_scaling


def test_direct_and_iterative_reach_the_same_residual():
    direct = solver_scaling.measure(0.4, "direct")
    iterative = solver_scaling.measure(0.4, "iterative")
    assert direct["dofs"] == iterative["dofs"] > 1000
    assert iterative["residual"] == pytest.approx(direct["residual"], rel=1e-5)
    assert direct["memory"] > 0 and iterative["first"] > 0 and iterative["next"] > 0
    for row in (direct, iterative):  # the parts timed apart lie within a later iteration
        assert set(row["parts"]) == set(solver_scaling.PARTS)
        assert 0 < sum(row["parts"].values()) <= row["next"]
    text = solver_scaling.report([direct, iterative])
    assert text.count(f"| {direct['dofs']} |") == 4  # the table and the parts' table


def test_the_exponent_is_the_slope_in_log_log():
    rows = [{"dofs": n, "next": 3.0 * n ** 1.2} for n in (1e5, 3e5, 1e6)]
    assert solver_scaling.exponent(rows, "next") == pytest.approx(1.2, rel=1e-12)
    assert solver_scaling.exponent(rows[:1], "next") is None
    assert math.isfinite(solver_scaling.exponent(rows[:2], "next"))


def test_a_rung_too_large_for_the_memory_is_predicted_from_the_last_smaller_one():
    rows = [{"solver": "direct", "ranks": 1, "resolution": r, "memory": m} for r, m in ((1.0, 1e8), (2.0, 2e9))]
    growth = 3 * solver_scaling.MEMORY_GROWTH
    assert solver_scaling.predicted_memory(rows, 4.0, "direct", 1) == pytest.approx(2e9 * 2 ** growth)
    assert solver_scaling.predicted_memory(rows, 4.0, "direct", 2) == 0.0  # nothing measured on 2 ranks
    assert solver_scaling.predicted_memory(rows, 0.5, "direct", 1) == 0.0  # nothing smaller
    assert 0 < solver_scaling.available_memory()
