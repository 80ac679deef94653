"""`femcontact study --scheduler slurm` on a real SLURM (`make test-slurm` starts a one-node cluster on
localhost with tests/slurm/cluster.sh and exports SLURM_CONF; skipped without it).

- an RCC study submitted through SLURM gives the same results.csv, row for row, as the same study run
  locally, ignoring only the columns that measure time (`time.*`, `wall`);
- one array task cancelled mid-run: its case has no result, a resubmission (while the other tasks still
  run) submits that case alone, and in the end every case ran exactly once, the cancelled one twice;
- shared prefixes run as a job array the case array depends on; cases of 2 MPI ranks under srun.
"""
import csv
import json
import os
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from femcontact.cli import main
from femcontact.study.slurm import active_tasks, read_submissions
from femcontact.study.study_file import load_study
from block_scene import BLOCK_SCENE

REPO = Path(__file__).resolve().parents[2]
FAKE_CASE = REPO / "tests" / "support" / "fake_case.py"
SRUN_FAKE = f"srun -n {{ranks}} {sys.executable} {FAKE_CASE}"
IGNORED = ("wall",)  # and every time.* column: measured durations

pytestmark = pytest.mark.skipif(not os.environ.get("SLURM_CONF"), reason="needs the test cluster: make test-slurm")

RCC_STUDY = f"""[study]
name = "rcc_slurm"
scene = "{REPO / 'scenes' / 'rcc.toml'}"
jobs = 2
[sweep]
grid = {{ "rcc.theta_l" = [60, 70, 80] }}
zip = {{ "motion.translation" = [0.1, 1.0], "motion.rotation" = [0.005, 0.05] }}
"""

FAKE_BASE = BLOCK_SCENE


@pytest.fixture(autouse=True)
def environment(tmp_path, monkeypatch):
    """Every array task inherits this environment (sbatch exports it)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    for knob in ("FAKE_SLEEP", "FAKE_FAIL_MU", "FAKE_CRASH_MU", "FAKE_HANG_MU", "FAKE_RANKS", "FAKE_FIELDS"):
        monkeypatch.delenv(knob, raising=False)
    calls = tmp_path / "calls"
    calls.mkdir()
    monkeypatch.setenv("FAKE_CALLS", str(calls))


def study_args(path, results, *options):
    return ["study", str(path), "--results", str(results), *options]


def submit(path, results, capsys, *options) -> list[str]:
    """Submit through SLURM; returns the job ids printed (none when nothing was left to submit)."""
    capsys.readouterr()
    assert main(study_args(path, results, "--scheduler", "slurm", *options)) == 0
    return capsys.readouterr().out.split()


def wait(study, timeout=300.0) -> None:
    """Until no recorded array task of the study is pending or running."""
    deadline = time.monotonic() + timeout
    while active_tasks(study):
        assert time.monotonic() < deadline, f"SLURM tasks still active after {timeout} s: {active_tasks(study)}"
        time.sleep(0.5)


def calls(tmp_path) -> dict:
    """Case (or prefix) id -> how many times its case process started."""
    counts = {}
    for path in (tmp_path / "calls").iterdir():
        counts[path.name.split(".")[0]] = counts.get(path.name.split(".")[0], 0) + 1
    return counts


def read_csv(path: Path) -> tuple[list[str], list[dict]]:
    with open(path) as stream:
        reader = csv.DictReader(stream)
        return reader.fieldnames, list(reader)


def test_rcc_study_through_slurm_equals_the_local_run(tmp_path, capsys):
    path = tmp_path / "rcc_slurm.toml"
    path.write_text(RCC_STUDY)
    assert main(study_args(path, tmp_path / "local", "--quiet")) == 0

    [job] = submit(path, tmp_path / "slurm", capsys)
    study = load_study(path, results_root=tmp_path / "slurm")
    wait(study)
    assert main(study_args(path, tmp_path / "slurm", "--status")) == 0
    assert capsys.readouterr().out.splitlines()[-1] == \
        "study rcc_slurm: 6 cases: 6 done, 0 without equilibrium, 0 failed, 0 running, 0 queued, 0 missing"
    for case in study.cases:  # each case ran in its array task of this job
        runner = json.loads((case.dir / "runner.json").read_text())
        assert runner["slurm"]["job"] == job and runner["command"][:3] == ["srun", "-n", "1"]

    local_columns, local_rows = read_csv(tmp_path / "local/rcc_slurm/results.csv")
    slurm_columns, slurm_rows = read_csv(tmp_path / "slurm/rcc_slurm/results.csv")
    assert slurm_columns == local_columns and len(slurm_rows) == len(local_rows) == 6
    compared = [c for c in local_columns if not c.startswith("time.") and c not in IGNORED]
    assert "centre_z" in compared and "max_rel_error" in compared and "git_commit" in compared
    for local, remote in zip(local_rows, slurm_rows):
        assert {c: remote[c] for c in compared} == {c: local[c] for c in compared}
    assert {row["status"] for row in slurm_rows} == {"ok"}

    with sqlite3.connect(tmp_path / "slurm/rcc_slurm/results.sqlite") as db:
        rows = db.execute("SELECT case_id, status, scene FROM cases").fetchall()
    assert sorted(r[0] for r in rows) == sorted(c.id for c in study.cases)
    assert all(status == "ok" and json.loads(scene)["kind"] == "rcc" for _, status, scene in rows)
    assert main(["report", str(path), "--results", str(tmp_path / "slurm")]) == 0
    assert "6 of 6 cases have results" in capsys.readouterr().out
    assert submit(path, tmp_path / "slurm", capsys) == []  # all done: nothing submitted

    # the runner itself in an allocation (docs/slurm.md, "Inside an allocation"): cases as srun steps
    script = tmp_path / "runner.sh"
    script.write_text(f"#!/bin/bash\n#SBATCH --ntasks=2 --time=00:10:00 --output={tmp_path}/runner.out\n"
                      f"{sys.executable} -m femcontact study {path} --results {tmp_path / 'alloc'} --jobs 2 "
                      "--launcher 'srun --exclusive -n {ranks}' --quiet\n")
    runner = subprocess.run(["sbatch", "--parsable", "--wait", str(script)], capture_output=True, text=True,
                            timeout=300)
    assert runner.returncode == 0, (tmp_path / "runner.out").read_text()
    alloc_columns, alloc_rows = read_csv(tmp_path / "alloc/rcc_slurm/results.csv")
    assert alloc_columns == local_columns and len(alloc_rows) == 6
    for local, inside in zip(local_rows, alloc_rows):
        assert {c: inside[c] for c in compared} == {c: local[c] for c in compared}
    for case in load_study(path, results_root=tmp_path / "alloc").cases:
        assert json.loads((case.dir / "runner.json").read_text())["command"][:4] == ["srun", "--exclusive", "-n", "1"]


def test_cancelled_task_is_resubmitted_alone_and_nothing_is_redone(tmp_path, monkeypatch, capsys):
    (tmp_path / "base.toml").write_text(FAKE_BASE)
    path = tmp_path / "demo.toml"
    path.write_text('[study]\nname = "demo"\nscene = "base.toml"\n'
                    '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6] }\n')
    monkeypatch.setenv("FAKE_SLEEP", "4")
    results = tmp_path / "results"
    [job] = submit(path, results, capsys, "--launcher", SRUN_FAKE, "--max-concurrent", "2")
    study = load_study(path, results_root=results)
    assert main(study_args(path, results, "--quiet")) == 2  # no local run while SLURM runs the study
    assert "queued or running in SLURM" in capsys.readouterr().err

    deadline = time.monotonic() + 120
    while not calls(tmp_path):  # the first case process has started
        assert time.monotonic() < deadline
        time.sleep(0.1)
    victim = next(case for case in study.cases if case.id in calls(tmp_path))
    index = read_submissions(study)[0]["ids"].index(victim.id)
    subprocess.run(["scancel", f"{job}_{index}"], check=True)
    deadline = time.monotonic() + 60
    while victim.id in active_tasks(study):
        assert time.monotonic() < deadline
        time.sleep(0.2)
    assert main(study_args(path, results, "--status")) == 0
    status = capsys.readouterr().out
    assert f"{victim.id}  missing" in status and " 0 missing" not in status and " 0 running" not in status

    [again] = submit(path, results, capsys, "--launcher", SRUN_FAKE, "--max-concurrent", "2")
    assert read_submissions(study)[1]["ids"] == [victim.id]  # the others are still in SLURM or done
    wait(study)
    assert main(study_args(path, results, "--status")) == 0
    assert capsys.readouterr().out.splitlines()[-1] == \
        "study demo: 6 cases: 6 done, 0 without equilibrium, 0 failed, 0 running, 0 queued, 0 missing"
    assert calls(tmp_path) == {case.id: 2 if case is victim else 1 for case in study.cases}
    for case in study.cases:
        result = json.loads((case.dir / "result.json").read_text())
        assert result["metrics"]["product"] == pytest.approx(case.scene["contact"]["mu"] * case.scene["contact"]["gamma"])
        assert json.loads((case.dir / "runner.json").read_text())["slurm"]["job"] == (again if case is victim else job)
    out = Path(read_submissions(study)[0]["script"]).parent / f"{job}_{index}.out"
    assert "stopped by SIGTERM; nothing recorded" in out.read_text()
    assert submit(path, results, capsys, "--launcher", SRUN_FAKE) == []


def test_shared_prefixes_first_and_cases_on_two_mpi_ranks(tmp_path, monkeypatch, capsys):
    (tmp_path / "base.toml").write_text(FAKE_BASE)
    path = tmp_path / "pulls.toml"
    path.write_text('[study]\nname = "pulls"\nscene = "base.toml"\nshared_steps = 1\n'
                    '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2], "steps.1.force" = [[5.0, -100.0], [10.0, -100.0]] }\n')
    monkeypatch.setenv("FAKE_RANKS", "2")  # the fake case checks MPI_COMM_WORLD's size (mpi4py)
    results = tmp_path / "results"
    prefix_job, case_job = submit(path, results, capsys, "--launcher", SRUN_FAKE, "--ranks-per-case", "2")
    study = load_study(path, results_root=results)
    prefixes, cases = read_submissions(study)
    assert f"#SBATCH --dependency=afterany:{prefix_job}\n" in Path(cases["script"]).read_text()
    assert "#SBATCH --ntasks=2\n" in Path(cases["script"]).read_text()
    wait(study)
    assert main(study_args(path, results, "--status")) == 0
    assert capsys.readouterr().out.splitlines()[-1] == \
        "study pulls: 4 cases: 4 done, 0 without equilibrium, 0 failed, 0 running, 0 queued, 0 missing"
    assert calls(tmp_path) == {identity: 1 for identity in prefixes["ids"] + cases["ids"]}
    assert len(prefixes["ids"]) == 2
    for case in study.cases:
        result = json.loads((case.dir / "result.json").read_text())
        assert result["status"] == "ok" and result["info"]["ranks"] == 2
        assert result["info"]["args"][-2:] == ["--restart", str((case.prefix.dir / "checkpoint").resolve())]
        runner = json.loads((case.dir / "runner.json").read_text())
        assert runner["slurm"]["job"] == case_job
