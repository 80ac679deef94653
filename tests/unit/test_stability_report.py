"""`make stability`'s report: converged cases far slower than their neighbours are named."""
from benchmarks.stability import COUNT_2D, COUNT_3D, RESOLUTIONS, cases, check, slow_cases, solve_kinds, study_report


def case(resolution: float, seconds: float, status: str = "ok", forms: float = 0.1):
    timings = {"forms": forms, "solve": seconds, "total": forms + seconds}
    return {"mesh": {"resolution": resolution}}, {"status": status, "timings": timings}


def test_a_case_whose_solve_takes_three_times_its_neighbours_is_named():
    results = {"a": case(1.0, 10.0), "b": case(1.1, 12.0), "c": case(0.9, 11.0), "slow": case(1.0, 40.0),
               "coarse": case(0.4, 2.0), "failed": case(1.0, 500.0, status="failed")}
    found = slow_cases(results)
    assert [cid for cid, _, _ in found] == ["slow"]
    assert found[0][2] == 40.0 / 11.0  # the median of a, b and c
    # a case far from every other resolution has no neighbours, and a failed case is not timed
    assert "coarse" not in {cid for cid, _, _ in found}


def test_a_slow_case_says_where_its_solve_time_went():
    solves = {"plain": {"solves": 5, "iterations": 20, "seconds": 1.0},
              "continuation": {"solves": 40, "iterations": 300, "seconds": 9.0},
              "failed": {"solves": 20, "iterations": 800, "seconds": 30.0}}
    assert solve_kinds({"info": {"newton_solves": solves}}) == (
        " (failed 30.0 s / 800 iterations, continuation 9.0 s / 300 iterations, plain 1.0 s / 20 iterations)")
    assert solve_kinds({"info": {}}) == ""  # a family that runs its own simulations writes no counts


def test_compiling_the_forms_does_not_make_a_case_slow():
    # a cold JIT cache adds about 4 s of form compilation to a 0.5 s solve
    results = {"a": case(1.0, 0.5), "b": case(1.1, 0.6), "c": case(0.9, 0.4), "cold": case(1.0, 0.5, forms=4.0)}
    assert slow_cases(results) == []


def answered(status: str, reason: str = "", **metrics):
    return {"status": status, "reason": reason, "metrics": metrics, "timings": {"total": 1.0}, "info": {}}


def test_a_load_without_static_equilibrium_is_an_answer_not_a_defect():
    no_equilibrium = answered("no_equilibrium", "step 'load': the push needs mu >= 0.067; the solver found none either",
                              friction_needed=0.067)
    assert check(no_equilibrium) is None
    assert check(answered("no_equilibrium")) == "no_equilibrium without a reason"
    assert check(answered("no_equilibrium", "needs mu >= 0.1", tilt=float("nan"))) == "non-finite metrics: tilt"
    assert check(answered("failed", "SimulationFailed: step load at t = 0.5 after 4 cuts; residual history [1.0]")) is None
    assert check(answered("failed", "ValueError: x")) == "unstructured failure: ValueError: x"
    assert check(None) == "no result"


def test_the_report_counts_ok_no_equilibrium_and_failed_apart():
    scene = {"mesh": {"resolution": 1.0}, "contact": {"mu": 0.0}}
    results = {"a": (scene, answered("ok")), "b": (scene, answered("ok")),
               "c": (scene, answered("no_equilibrium", "needs mu >= 0.067")),
               "d": (scene, answered("failed", "SimulationFailed: step load; residual history [1.0]")),
               "e": (scene, None)}
    lines, defects = study_report("sweep", results, dict.fromkeys(results))
    assert lines[0] == ("## sweep: 3 of 5 answered (60 %): 2 ok, 1 without a static equilibrium, 1 failed, "
                        "1 without a result; 1 defects (NaN, traceback, unstructured failure, no result)")
    assert defects == 1  # the case without a result
    assert "| c | no_equilibrium | 0 | - | needs mu >= 0.067 |" in lines
    # split by the rigid two-point statics: where mu is below what the load needs, no_equilibrium is the answer
    lines, _ = study_report("sweep", results, {**dict.fromkeys(results), "c": 0.067, "d": 0.0})
    assert ("- 1 cases with a rigid two-point equilibrium (mu >= the friction it needs): 0 ok, 0 without a static "
            "equilibrium, 1 failed") in lines
    assert ("- 1 cases without one (the rigid peg slides: mu < the friction it needs): 0 ok, 1 without a static "
            "equilibrium, 0 failed") in lines


def test_the_default_sweep_spans_the_meshes_users_reach():
    """120 2-D cases from resolution 0.35 to 2.0 and 12 3-D cases from 0.35 to 0.7, both ends reached."""
    rows_2d, rows_3d = cases(COUNT_2D, COUNT_3D, seed=1)
    assert (len(rows_2d), len(rows_3d)) == (120, 12)
    for rows, (low, high) in ((rows_2d, RESOLUTIONS[2]), (rows_3d, RESOLUTIONS[3])):
        resolutions = [row["mesh.resolution"] for row in rows]
        assert low * 0.999 <= min(resolutions) < low * 1.15 and high / 1.15 < max(resolutions) <= high * 1.001
    assert cases(COUNT_2D, COUNT_3D, seed=2)[0] != rows_2d  # another seed, other cases


def test_the_report_opens_with_one_outcomes_row_per_sweep(monkeypatch):
    """The section `make docs` copies into docs/stability.md (benchmarks/docs_update.py)."""
    import benchmarks.stability as stability
    from benchmarks.docs_update import section

    scene = {"mesh": {"resolution": 1.0}, "contact": {"mu": 0.5}}
    sweeps = {"stability": {"a": (scene, answered("ok")), "c": (scene, answered("no_equilibrium", "needs mu >= 0.6")),
                            "d": (scene, answered("failed", "SimulationFailed: step load; residual history [1.0]")),
                            "e": (scene, None)},
              "stability_3d": {"f": (scene, answered("ok"))}}
    monkeypatch.setattr(stability, "read_results", lambda name, rows, scene_path: sweeps[name])
    monkeypatch.setattr(stability, "friction_needed", lambda scene: None)
    text, found = stability.report([("stability", [], None), ("stability_3d", [], None)], "python -m benchmarks.stability")
    assert found == 1  # the case without a result
    assert section(text, "Outcomes").strip().splitlines() == [
        "The cases `python -m benchmarks.stability` draws, each run by the study runner:", "",
        "| sweep | cases | ok | no static equilibrium | failed | without a result | defects |",
        "|:---|---:|---:|---:|---:|---:|---:|",
        "| stability | 4 | 1 | 1 | 1 | 1 | 1 |",
        "| stability_3d | 1 | 1 | 0 | 0 | 0 | 0 |"]
