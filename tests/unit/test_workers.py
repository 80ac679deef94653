"""Warm workers of the study runner (femcontact/study/workers.py): a case run in a worker gives
the result of a fresh `mpirun -n 1 femcontact run`, bit for bit, also after another case ran in
the same process; a worker that crashes or passes the time limit fails its case with the reason
and is replaced, and the sweep goes on."""
import json
import os
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from femcontact.cli import main
from femcontact.io import remove_stale_compilations
from femcontact.study import workers
from block_scene import BLOCK_SCENE

ROOT = Path(__file__).resolve().parents[2]
SUPPORT = ROOT / "tests" / "support"
MPI_ENVIRONMENT = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
                   "OMPI_MCA_rmaps_base_oversubscribe": "1"}


def run_study(path, results, *options) -> int:
    return main(["study", str(path), "--results", str(results), "--quiet", *options])


def cases_of(results: Path, name: str) -> dict:
    """{case id: (scene, result, runner record)} of a study's results."""
    cases = {}
    for directory in (results / name / "cases").iterdir():
        cases[directory.name] = (tomllib.loads((directory / "scene.toml").read_text()),
                                 json.loads((directory / "result.json").read_text()),
                                 json.loads((directory / "runner.json").read_text()))
    return cases


def test_worker_results_equal_fresh_processes_bit_for_bit(tmp_path, monkeypatch):
    """Two real 2-D wedging cases (632 dofs) back to back in one worker, then each in its own
    `mpirun -n 1`. The first sets a PETSc option (the MUMPS ordering) that the second does not:
    left set, it would change the second case's factorisation and so its last digits."""
    for name, value in MPI_ENVIRONMENT.items():
        monkeypatch.setenv(name, value)
    coarse = ('[scene]\nmesh.resolution = 0.3\n"steps.0.increments" = 2\n"steps.1.increments" = 2\n'
              '[sweep]\ncases = [{ "contact.mu" = 0.3, "solver.petsc_options.mat_mumps_icntl_7" = 4 }, '
              '{ "contact.mu" = 0.2 }]\n')
    for mode in ("warm", "fresh"):
        (tmp_path / f"{mode}.toml").write_text(
            f'[study]\nname = "{mode}"\nscene = "{ROOT / "scenes/wedging_2d.toml"}"\njobs = 1\n'
            f'workers = {"true" if mode == "warm" else "false"}\n' + coarse)
        assert run_study(tmp_path / f"{mode}.toml", tmp_path / "results") == 0
    warm, fresh = cases_of(tmp_path / "results", "warm"), cases_of(tmp_path / "results", "fresh")
    assert set(warm) == set(fresh) and len(warm) == 2
    assert len({record["worker"] for _, _, record in warm.values()}) == 1  # one process ran both
    assert {record["worker"] for _, _, record in fresh.values()} == {None}
    assert {record["command"][0] for _, _, record in fresh.values()} == {"mpirun"}
    for case, (scene, result, _) in warm.items():
        assert result["status"] == "ok" and result["metrics"]["increments"] == 4
        timing = {"wall_time_s"}  # the family's own time measurement
        assert result["metrics"].keys() == fresh[case][1]["metrics"].keys()
        assert {key: value for key, value in result["metrics"].items() if key not in timing} == \
            {key: value for key, value in fresh[case][1]["metrics"].items() if key not in timing}, scene["contact"]
        history = (tmp_path / "results/warm/cases" / case / "history.csv").read_text()
        assert history == (tmp_path / "results/fresh/cases" / case / "history.csv").read_text()


@pytest.fixture
def fake_worker(tmp_path, monkeypatch):
    """Workers that run tests/support/fake_case.py instead of `femcontact run` (nothing preloaded)."""
    monkeypatch.setattr(workers, "ENTRY", "fake_case:worker_main")
    monkeypatch.setattr(workers, "PRELOAD", ())
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(SUPPORT), str(ROOT), os.environ.get("PYTHONPATH", "")]))
    for knob in ("FAKE_CALLS", "FAKE_SLEEP", "FAKE_FAIL_MU", "FAKE_RANKS", "FAKE_FIELDS"):
        monkeypatch.delenv(knob, raising=False)
    (tmp_path / "base.toml").write_text(BLOCK_SCENE)


def test_a_crashed_or_hanging_worker_fails_its_case_and_is_replaced(tmp_path, monkeypatch, fake_worker):
    monkeypatch.setenv("FAKE_CRASH_MU", "0.2")  # os._exit(139) in the middle of the case
    monkeypatch.setenv("FAKE_HANG_MU", "0.4")  # sleeps past the time limit
    path = tmp_path / "demo.toml"
    path.write_text('[study]\nname = "demo"\nscene = "base.toml"\njobs = 1\ntime_limit = 1.5\n'
                    '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4, 0.5] }\n')
    assert run_study(path, tmp_path / "results") == 1
    runs = sorted(cases_of(tmp_path / "results", "demo").values(), key=lambda case: case[0]["contact"]["mu"])
    mu = [scene["contact"]["mu"] for scene, _, _ in runs]
    status = [result["status"] for _, result, _ in runs]
    pids = [record["worker"] for _, _, record in runs]
    assert mu == [0.1, 0.2, 0.3, 0.4, 0.5] and status == ["ok", "failed", "ok", "failed", "ok"]
    assert runs[1][1]["reason"] == ("exited with code 139 without a result; "
                                    "last log line: fake case: segmentation fault (pretend)")
    assert runs[3][1]["reason"] == "time limit of 1.5 s exceeded"
    assert runs[3][1] == {"status": "failed", "reason": "time limit of 1.5 s exceeded", "metrics": {},
                          "timings": {}, "info": {"ranks": 1}}
    assert pids[0] == pids[1] != pids[2] == pids[3] != pids[4]  # replaced after the crash and the kill
    assert not any(Path(f"/proc/{pid}").exists() for pid in pids)  # no worker left behind


def test_a_worker_is_replaced_after_its_share_of_cases(tmp_path, monkeypatch, fake_worker):
    monkeypatch.setattr(workers, "CASES_PER_WORKER", 2)
    path = tmp_path / "demo.toml"
    path.write_text('[study]\nname = "demo"\nscene = "base.toml"\njobs = 1\n'
                    '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3] }\n')
    assert run_study(path, tmp_path / "results") == 0
    runs = sorted(cases_of(tmp_path / "results", "demo").values(), key=lambda case: case[0]["contact"]["mu"])
    pids = [record["worker"] for _, _, record in runs]
    assert pids[0] == pids[1] != pids[2] and not any(Path(f"/proc/{pid}").exists() for pid in pids)


def test_worker_exit_codes_and_log_match_a_process(tmp_path, monkeypatch, fake_worker):
    """A failing case (exit 1, its own result) and bad input (exit 2, no result: the runner
    records the code and the log's last line) end in a worker as in a fresh process."""
    monkeypatch.setenv("FAKE_FAIL_MU", "0.1")
    path = tmp_path / "demo.toml"
    path.write_text('[study]\nname = "demo"\nscene = "base.toml"\njobs = 2\n'
                    '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2] }\n')
    assert run_study(path, tmp_path / "results") == 1
    runs = {scene["contact"]["mu"]: result for scene, result, _ in cases_of(tmp_path / "results", "demo").values()}
    assert runs[0.1]["reason"] == "NewtonDiverged: no convergence at mu = 0.1" and runs[0.2]["status"] == "ok"

    monkeypatch.setattr(workers, "ENTRY", "femcontact.cli:main")  # the real command on a bad scene
    directory = tmp_path / "bad"
    directory.mkdir()
    (directory / "scene.toml").write_text('kind = "contact"\ndim = 4\n')
    pool = workers.Pool(lambda slot: dict(os.environ))
    worker = pool.worker(0)
    worker.submit(directory, ["run", "scene.toml", "--out", "."])
    deadline = time.monotonic() + 60
    while (code := worker.poll()) is None and time.monotonic() < deadline:
        time.sleep(0.02)
    fresh = subprocess.run([sys.executable, "-m", "femcontact", "run", "scene.toml", "--out", "."], cwd=directory,
                           capture_output=True, text=True)
    assert code == fresh.returncode == 2 and worker.alive and not (directory / "result.json").exists()
    assert (directory / "log.txt").read_text() == fresh.stdout + fresh.stderr
    assert "dim = 4: not allowed" in fresh.stderr
    pool.close()
    assert not worker.alive


def test_clean_up_restores_petsc_options_and_ufl_counters():
    """Between cases a worker puts back the PETSc options and UFL's object counters (a case run
    later in the process then builds the forms a fresh process builds, with the same signatures)."""
    import ufl
    from petsc4py import PETSc

    baseline = workers.process_state()
    PETSc.Options()["femcontact_test_pc_type"] = "jacobi"
    mesh = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))
    ufl.Constant(mesh), ufl.Coefficient(ufl.FunctionSpace(mesh, ufl.FiniteElement("Lagrange", ufl.triangle, 1)))
    ufl.indices(3)
    changed = workers.process_state()
    assert changed["petsc"] != baseline["petsc"] and changed["ufl"] != baseline["ufl"]
    del mesh
    workers.clean_up(baseline)
    assert workers.process_state() == baseline


def test_stale_compilations_are_removed_and_compiled_ones_kept(tmp_path):
    """femcontact run's JIT cache clean-up (one directory listing for the whole cache)."""
    names = ["a.c", "a.c.cached", "a.cpython-311-x86_64-linux-gnu.so", "b.c", "b.so", "c.c", "c.c.cached",
             "e.c.cached", "e.so", "d.c", "d.c.cached"]
    for name in names:
        (tmp_path / name).write_text("")
    old = time.time() - 3600
    for name in names[:-2]:
        os.utime(tmp_path / name, (old, old))
    remove_stale_compilations(tmp_path, older_than=600)
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(set(names) - {"c.c", "c.c.cached",
                                                                                  "e.c.cached"})


def test_two_runners_never_share_a_job_slot(tmp_path):
    """Two studies run at once: each runner holds its slots' JIT caches (file locks), so one never
    cleans the other's compilation in progress."""
    from femcontact.study.runner import take_slot

    first = [take_slot(tmp_path) for _ in range(2)]
    second = [take_slot(tmp_path) for _ in range(2)]
    assert [name for name, _ in first + second] == ["slot-0", "slot-1", "slot-2", "slot-3"]
    first[0][1].close()
    assert take_slot(tmp_path)[0] == "slot-0"
