"""`make stability`'s report: converged cases far slower than their neighbours are named."""
from femcontact.scenarios.stability import slow_cases


def case(resolution: float, seconds: float, status: str = "ok"):
    return {"mesh": {"resolution": resolution}}, {"status": status, "timings": {"total": seconds}}


def test_a_case_slower_than_three_times_its_neighbours_is_named():
    results = {"a": case(1.0, 10.0), "b": case(1.1, 12.0), "c": case(0.9, 11.0), "slow": case(1.0, 40.0),
               "coarse": case(0.4, 2.0), "failed": case(1.0, 500.0, status="failed")}
    found = slow_cases(results)
    assert [cid for cid, _, _ in found] == ["slow"]
    assert found[0][2] == 40.0 / 11.0  # the median of a, b and c
    # a case far from every other resolution has no neighbours, and a failed case is not timed
    assert "coarse" not in {cid for cid, _, _ in found}
