"""`femcontact study --scheduler slurm` without a SLURM: the sbatch script, the array index -> case
mapping, which cases a resubmission selects, `--status`, and what an array task records when its case
crashes, is cancelled or its shared prefix failed.

`sbatch` and `squeue` are stand-ins on PATH: sbatch keeps the script and answers job ids 100, 101, ...;
squeue prints the lines of $FAKE_SQUEUE ("JOB|INDICES|STATE"). The array tasks are run directly
(`python -m femcontact.study.slurm task MANIFEST INDEX`) with tests/support/fake_case.py as the case. The real
cluster test is tests/slurm/ (`make test-slurm`).
"""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from femcontact.cli import main
from femcontact.errors import InputError
from femcontact.study.slurm import (active_tasks, default_time, expand_indices, parse_time, read_submissions,
                              sbatch_script, select)
from femcontact.study.study_file import load_study

HERE = Path(__file__).parent
SUPPORT = HERE.parent / "support"
from test_study import FAKE, make_study  # noqa: E402  (the study runner's fake case and study files)

SBATCH = """#!/bin/bash
n=$(ls "$FAKE_SBATCH_DIR" | wc -l)
cp "${@: -1}" "$FAKE_SBATCH_DIR/$((100 + n)).sh"
echo "$((100 + n))"
"""
SQUEUE = """#!/bin/bash
cat "$FAKE_SQUEUE"
"""


@pytest.fixture
def cluster(tmp_path, monkeypatch):
    """Stand-in sbatch/squeue on PATH; returns (submitted scripts dir, squeue answer file)."""
    bin_dir, scripts, answer = tmp_path / "bin", tmp_path / "sbatch", tmp_path / "squeue.txt"
    bin_dir.mkdir()
    scripts.mkdir()
    answer.write_text("")
    for name, text in (("sbatch", SBATCH), ("squeue", SQUEUE)):
        (bin_dir / name).write_text(text)
        (bin_dir / name).chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")
    monkeypatch.setenv("FAKE_SBATCH_DIR", str(scripts))
    monkeypatch.setenv("FAKE_SQUEUE", str(answer))
    for knob in ("FAKE_SLEEP", "FAKE_FAIL_MU", "FAKE_CRASH_MU", "FAKE_HANG_MU", "FAKE_RANKS", "FAKE_FIELDS",
                 "FAKE_CALLS"):
        monkeypatch.delenv(knob, raising=False)
    return scripts, answer


def submit(path, *options) -> int:
    return main(["study", str(path), "--results", str(path.parent / "results"), "--scheduler", "slurm",
                 "--launcher", FAKE + " -n {ranks}", "--quiet", *options])


def run_task(manifest, index, **env) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "femcontact.study.slurm", "task", str(manifest), str(index)],
                          env={**os.environ, **env}, capture_output=True, text=True, timeout=60)


MU4 = '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4] }'


def test_sbatch_script_has_the_array_resources_and_task_command(tmp_path):
    text = sbatch_script(name="demo", kind="case", count=5, ranks=3, manifest=tmp_path / "m.json",
                         output_dir=tmp_path, time_limit="01:30:00", partition="short", max_concurrent=2,
                         dependency="afterany:41", python="/venv/bin/python")
    directives = [line.split(None, 1)[1] for line in text.splitlines() if line.startswith("#SBATCH")]
    assert directives == ["--job-name=femcontact-demo", "--array=0-4%2", "--ntasks=3", "--cpus-per-task=1",
                          "--time=01:30:00", f"--output={tmp_path}/%A_%a.out", "--partition=short",
                          "--dependency=afterany:41"]
    assert text.splitlines()[-1] == (f"exec /venv/bin/python -m femcontact.study.slurm task {tmp_path / 'm.json'} "
                                     '"$SLURM_ARRAY_TASK_ID"')
    assert subprocess.run(["bash", "-n"], input=text, text=True).returncode == 0
    plain = sbatch_script(name="demo", kind="prefix", count=1, ranks=1, manifest=tmp_path / "m.json",
                          output_dir=tmp_path, time_limit="10")
    assert "--array=0-0\n" in plain and "--partition" not in plain and "--dependency" not in plain
    assert "--job-name=femcontact-demo-prefix" in plain


def test_times_and_array_indices():
    assert default_time(600.0) == "00:15:00" and default_time(7200.0) == "02:05:00"
    assert parse_time("1-12:00:00") == "1-12:00:00" and parse_time("30") == "30"
    with pytest.raises(InputError, match="--time '1h'"):
        parse_time("1h")
    assert expand_indices("3") == [3] and expand_indices("0-4%2") == [0, 1, 2, 3, 4]
    assert expand_indices("[1,3-5%2]") == [1, 3, 4, 5]


def test_bad_time_is_an_input_error(tmp_path, cluster, capsys):
    path = make_study(tmp_path, MU4)
    assert submit(path, "--time", "soon") == 2
    assert "--time 'soon'" in capsys.readouterr().err
    assert list(cluster[0].iterdir()) == []


def test_array_index_maps_to_its_case(tmp_path, cluster, capsys):
    path = make_study(tmp_path, MU4)
    assert submit(path, "--ranks-per-case", "2", "--max-concurrent", "3") == 0
    assert capsys.readouterr().out.split() == ["100"]
    study = load_study(path, results_root=tmp_path / "results")
    [submission] = read_submissions(study)
    assert submission["job"] == "100" and submission["ids"] == [case.id for case in study.cases]
    manifest = json.loads((Path(submission["script"]).parent / "manifest.json").read_text())
    assert [Path(task["dir"]) for task in manifest["tasks"]] == [case.dir.resolve() for case in study.cases]
    script = (cluster[0] / "100.sh").read_text()
    assert "--array=0-3%3" in script and "--ntasks=2" in script and "--time=00:15:00" in script
    assert (study.cases[2].dir / "scene.toml").exists() and not (study.cases[2].dir / "result.json").exists()

    done = run_task(Path(submission["script"]).parent / "manifest.json", 2, SLURM_ARRAY_JOB_ID="100")
    assert done.returncode == 0, done.stderr
    result = json.loads((study.cases[2].dir / "result.json").read_text())
    assert result["metrics"]["product"] == pytest.approx(0.3 * study.cases[2].scene["contact"]["gamma"])
    assert result["info"]["ranks"] == 2  # the launcher got -n 2
    runner = json.loads((study.cases[2].dir / "runner.json").read_text())
    assert runner["slurm"] == {"job": "100", "task": 2, "node": os.uname().nodename}
    assert runner["slot"] == "slurm-slot-0" and runner["wall"] > 0
    assert [case.dir.joinpath("result.json").exists() for case in study.cases] == [False, False, True, False]


def test_resubmission_selects_only_missing_and_failed_never_active(tmp_path, cluster, capsys):
    scripts, answer = cluster
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4, 0.5] }')
    assert submit(path) == 0
    study = load_study(path, results_root=tmp_path / "results")
    manifest = Path(read_submissions(study)[0]["script"]).parent / "manifest.json"
    # task 0 ok, task 1 failed (the case raises), task 2 running, task 3 pending, task 4 cancelled (gone)
    assert run_task(manifest, 0).returncode == 0
    assert run_task(manifest, 1, FAKE_FAIL_MU="0.2").returncode == 1
    answer.write_text("100|2|RUNNING\n100|3|PENDING\n101|0|PENDING\n")  # 101: another user's job
    cases = study.cases
    assert active_tasks(study) == {cases[2].id: {"job": "100", "index": 2, "state": "RUNNING"},
                                   cases[3].id: {"job": "100", "index": 3, "state": "PENDING"}}
    capsys.readouterr()
    assert main(["study", str(path), "--results", str(tmp_path / "results"), "--status"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in lines[:5]] == [[cases[0].id, "ok"], [cases[1].id, "failed"],
                                                      [cases[2].id, "running"], [cases[3].id, "queued"],
                                                      [cases[4].id, "missing"]]
    assert lines[2].endswith("[job 100_2]")
    assert lines[5] == "study demo: 5 cases: 1 done, 0 without equilibrium, 1 failed, 1 running, 1 queued, 1 missing"
    assert (tmp_path / "results/demo/results.csv").read_text().count("\n") == 3  # header + 2 results

    assert [c.id for c in select(study, active_tasks(study), False, False)[0]] == [cases[4].id]
    assert [c.id for c in select(study, active_tasks(study), True, False)[0]] == [cases[1].id, cases[4].id]
    assert submit(path, "--retry-failed") == 0
    assert capsys.readouterr().out.split() == ["101"]
    assert read_submissions(study)[1]["ids"] == [cases[1].id, cases[4].id]
    assert "--array=0-1%2\n" in (scripts / "101.sh").read_text()  # at most `jobs` (2) at once
    answer.write_text("100|2|RUNNING\n100|3|PENDING\n101|0-1%2|PENDING\n")
    assert submit(path, "--retry-failed") == 0 and capsys.readouterr().out == ""  # nothing left to submit
    assert main(["study", str(path), "--results", str(tmp_path / "results"), "--quiet"]) == 2
    assert "4 case(s) of this study are queued or running in SLURM (job 100, 101)" in capsys.readouterr().err


def test_task_records_a_crash_but_not_a_cancellation(tmp_path, cluster):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2] }')
    assert submit(path) == 0
    study = load_study(path, results_root=tmp_path / "results")
    manifest = Path(read_submissions(study)[0]["script"]).parent / "manifest.json"
    assert run_task(manifest, 0, FAKE_CRASH_MU="0.1").returncode == 1
    crashed = json.loads((study.cases[0].dir / "result.json").read_text())
    assert crashed["status"] == "failed" and crashed["reason"].startswith("exited with code 139 without a result")

    calls = tmp_path / "calls"
    calls.mkdir()
    task = subprocess.Popen([sys.executable, "-m", "femcontact.study.slurm", "task", str(manifest), "1"],
                            env={**os.environ, "FAKE_HANG_MU": "0.2", "FAKE_CALLS": str(calls)},
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while not list(calls.iterdir()) and time.monotonic() < deadline:
        time.sleep(0.05)
    task.send_signal(signal.SIGTERM)  # what scancel and a job's time limit do
    assert task.wait(20) == 143
    assert "stopped by SIGTERM; nothing recorded" in task.stderr.read()
    assert not (study.cases[1].dir / "result.json").exists()
    assert [c.id for c in select(study, {}, False, False)[0]] == [study.cases[1].id]


def test_prefix_job_first_and_cases_follow_its_result(tmp_path, cluster, capsys):
    scripts, _ = cluster
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2], "steps.1.force" = [[1.0, -100.0], '
                                '[2.0, -100.0]] }', settings="shared_steps = 1")
    assert submit(path) == 0
    assert capsys.readouterr().out.split() == ["100", "101"]  # the prefixes, then the cases after them
    assert "--dependency=afterany:100" in (scripts / "101.sh").read_text()
    study = load_study(path, results_root=tmp_path / "results")
    prefixes, cases = read_submissions(study)
    assert prefixes["kind"] == "prefix" and len(prefixes["ids"]) == 2 and len(cases["ids"]) == 4
    prefix_manifest = Path(prefixes["script"]).parent / "manifest.json"
    case_manifest = Path(cases["script"]).parent / "manifest.json"
    by_id = {case.id: case for case in study.cases}
    first = by_id[cases["ids"][0]]
    prefix_index = prefixes["ids"].index(first.prefix.id)
    assert run_task(case_manifest, 0).returncode == 1  # prefix not run: nothing recorded
    assert not (first.dir / "result.json").exists()
    assert run_task(prefix_manifest, prefix_index, FAKE_FAIL_MU=str(first.scene["contact"]["mu"])).returncode == 1
    assert run_task(case_manifest, 0).returncode == 1
    result = json.loads((first.dir / "result.json").read_text())
    assert result["reason"].startswith(f"shared prefix {first.prefix.id} failed: NewtonDiverged")

    assert run_task(prefix_manifest, prefix_index).returncode == 0  # the prefix again, ok
    assert run_task(case_manifest, 0).returncode == 0
    assert json.loads((first.dir / "result.json").read_text())["info"]["args"][-2] == "--restart"
