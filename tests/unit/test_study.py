"""The study runner: case ids, sweep expansion, resume after SIGKILL, failures, time limit,
database and CSV, MPI cases, shared prefixes, plots and snapshots.

Cases run through a fake launcher (tests/support/fake_case.py) that writes result.json like
`femcontact run` does, so these tests depend neither on the solver nor on the RCC code.
"""
import csv
import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time
import tomllib
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from femcontact.cli import main
from femcontact.study.database import Database
from femcontact.errors import InputError
from femcontact.config.scene import case_id
from femcontact.families import resolve_scene
from femcontact.config.schema import set_key
from femcontact.study.study_file import count_cases, expand, load_study, to_toml
from block_scene import BLOCK_SCENE

HERE = Path(__file__).parent
SUPPORT = HERE.parent / "support"
FAKE = f"{sys.executable} {SUPPORT / 'fake_case.py'}"
PNG = b"\x89PNG\r\n\x1a\n"

BASE = BLOCK_SCENE


def make_study(tmp_path, body: str, name="demo", launcher=FAKE + " -n {ranks}", settings="") -> Path:
    (tmp_path / "base.toml").write_text(BASE)
    path = tmp_path / f"{name}.toml"
    path.write_text(f'[study]\nname = "{name}"\nscene = "base.toml"\njobs = 2\nlauncher = "{launcher}"\n'
                    f"{settings}\n{body}")
    return path


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """Environment of the fake case; returns a function counting invocations per case id."""
    calls = tmp_path / "calls"
    calls.mkdir()
    monkeypatch.setenv("FAKE_CALLS", str(calls))
    for knob in ("FAKE_SLEEP", "FAKE_FAIL_MU", "FAKE_NO_EQUILIBRIUM_MU", "FAKE_CRASH_MU", "FAKE_HANG_MU", "FAKE_RANKS",
                 "FAKE_FIELDS"):
        monkeypatch.delenv(knob, raising=False)

    def count() -> dict:
        counts = {}
        for path in calls.iterdir():
            counts[path.name.split(".")[0]] = counts.get(path.name.split(".")[0], 0) + 1
        return counts

    return count


def run_study(path, *options) -> int:
    return main(["study", str(path), "--results", str(path.parent / "results"), "--quiet", *options])


def results_of(path, name="demo") -> dict:
    cases = path.parent / "results" / name / "cases"
    return {d.name: json.loads((d / "result.json").read_text()) for d in cases.iterdir()
            if (d / "result.json").exists()} if cases.exists() else {}


# -- case ids, overrides, expansion ---------------------------------------------------------------

def test_case_id_ignores_order_and_formatting_not_values():
    a = resolve_scene(tomllib.loads(BASE))
    b = resolve_scene(tomllib.loads('geometry="block"\n  dim=2\n[[steps]]\nforce=[0, -1e2]\nname="press"\n'
                              '[[steps]]\nname="pull"\nforce=[10, -100.0]\n[contact]\nmu=0.20\n'))
    assert case_id(a) == case_id(b)
    changed = resolve_scene(tomllib.loads(BASE.replace("mu = 0.2", "mu = 0.2000001")))
    assert case_id(changed) != case_id(a)
    assert case_id(resolve_scene(tomllib.loads(BASE), ["steps.1.force=[10.0, -100.5]"])) != case_id(a)


def test_set_key_indexes_arrays():
    data = tomllib.loads(BASE)
    set_key(data, "steps.1.force", [1.0, 2.0])
    set_key(data, "steps.0.pulse.frequency", 5.0)
    assert data["steps"][1]["force"] == [1.0, 2.0] and data["steps"][0]["pulse"] == {"frequency": 5.0}
    with pytest.raises(InputError, match="steps.2.force"):
        set_key(data, "steps.2.force", [0.0, 0.0])
    with pytest.raises(InputError, match="contact.mu.x"):
        set_key(data, "contact.mu.x", 1)


def test_scene_toml_round_trip_keeps_the_case_id():
    scene = resolve_scene(tomllib.loads(BASE), ['solver.petsc_options={ksp_type = "preonly", "pc_x.y" = 1}'])
    again = resolve_scene(tomllib.loads(to_toml(scene)))
    assert again == scene and case_id(again) == case_id(scene)


def test_expand_grid_times_zip_plus_cases():
    sweep = {"grid": {"a": [1, 2], "b": {"c": [3, 4, 5]}}, "zip": {"x": [6, 7], "y": [8, 9]},
             "cases": [{"a": 0}]}
    sets = list(expand(sweep))
    assert len(sets) == 2 * 3 * 2 + 1
    assert sets[0] == {"a": 1, "b.c": 3, "x": 6, "y": 8} and sets[1] == {"a": 1, "b.c": 3, "x": 7, "y": 9}
    assert sets[-1] == {"a": 0}
    assert list(expand({})) == [{}] and list(expand({"cases": [{"a": 1}]})) == [{"a": 1}]
    assert count_cases(sweep) == 13 and count_cases({}) == 1 and count_cases({"cases": [{"a": 1}]}) == 1


def test_study_validates_every_case_before_running(tmp_path, fake):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, -1.0], "steps.1.force" = [[1.0, 2.0]] }\n'
                                'zip = { "contact.gamma" = [1.0, 2.0], "mesh.degree" = [1, 2] }')
    with pytest.raises(InputError, match=r"2 invalid case\(s\), nothing was run:\n  contact.mu = -1.0: out of range.* \(2 cases: "
                       r"contact.mu=-1.0, .*mesh.degree=1; contact.mu=-1.0, .*mesh.degree=2\)$"):
        load_study(path, results_root=tmp_path / "results")
    path.write_text(path.read_text().replace("-1.0", "0.3"))
    study = load_study(path, ["contact.theta=1"], results_root=tmp_path / "results")
    assert len(study.cases) == 4 and study.keys == ["contact.mu", "steps.1.force", "contact.gamma", "mesh.degree"]
    assert {case.scene["contact"]["theta"] for case in study.cases} == {1.0}
    make_study(tmp_path, '[sweep]\nzip = { "contact.gamma" = [1.0, 2.0], "mesh.degree" = [1] }')
    with pytest.raises(InputError, match="zipped lists must have one length"):
        load_study(tmp_path / "demo.toml")
    assert fake() == {}


# -- running --------------------------------------------------------------------------------------

def test_failures_do_not_stop_the_sweep_and_csv_matches_database(tmp_path, fake, monkeypatch, capsys):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4] }')
    monkeypatch.setenv("FAKE_FAIL_MU", "0.2")
    monkeypatch.setenv("FAKE_CRASH_MU", "0.3")
    assert run_study(path) == 1
    out = capsys.readouterr().out
    assert "4 cases, 2 ok, 0 without equilibrium, 2 failed" in out and "NewtonDiverged: no convergence at mu = 0.2" in out
    results = results_of(path)
    cases = path.parent / "results/demo/cases"
    by_mu = {tomllib.loads((cases / i / "scene.toml").read_text())["contact"]["mu"]: r for i, r in results.items()}
    assert by_mu[0.1]["status"] == by_mu[0.4]["status"] == "ok"
    assert "exited with code 139 without a result; last log line: fake case: segmentation fault" \
        in by_mu[0.3]["reason"]

    database = Database(path.parent / "results/demo/results.sqlite", ["contact.mu"])
    with open(path.parent / "results/demo/results.csv") as stream:
        table = list(csv.DictReader(stream))
    rows = database.rows(database.csv_columns())
    assert [list(row) for row in table][0][:5] == ["case_id", "status", "contact.mu", "load", "product"]
    assert [{k: "" if v is None else str(v) for k, v in row.items()} for row in rows] == table
    assert {row["case_id"] for row in rows} == set(results) and rows[0]["dolfinx"] == "0.5.2"

    monkeypatch.delenv("FAKE_FAIL_MU")
    monkeypatch.delenv("FAKE_CRASH_MU")
    assert run_study(path) == 1 and sum(fake().values()) == 4  # failed cases are done, not rerun
    assert run_study(path, "--retry-failed") == 0 and sum(fake().values()) == 6
    assert run_study(path, "--force") == 0 and set(fake().values()) == {2, 3}


def test_time_limit_kills_a_hanging_case(tmp_path, fake, monkeypatch):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.5] }', settings="time_limit = 1")
    monkeypatch.setenv("FAKE_HANG_MU", "0.5")
    assert run_study(path) == 1
    reasons = sorted(str(r["reason"]) for r in results_of(path).values())
    assert reasons == ["None", "time limit of 1 s exceeded"]


def test_resume_after_sigkill_recomputes_nothing(tmp_path, fake):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3, 0.4, 0.5], '
                                '"contact.gamma" = [1.0, 2.0, 3.0, 4.0] }')
    env = {**os.environ, "FAKE_SLEEP": "0.4"}
    command = [sys.executable, "-m", "femcontact", "study", str(path), "--results", str(tmp_path / "results")]
    runner = subprocess.Popen(command, env=env, stderr=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # kill when >= 5 cases are done and one has just started (FAKE_SLEEP)
        done = set(results_of(path))
        started = [call.name.split(".")[0] for call in (tmp_path / "calls").iterdir()
                   if time.time() - call.stat().st_mtime < 0.2]
        interrupted = set(started) - done
        if len(done) >= 5 and interrupted:
            break
        time.sleep(0.02)
    runner.send_signal(signal.SIGKILL)
    runner.wait()
    finished = set(results_of(path))
    assert 5 <= len(finished) < 20
    with sqlite3.connect(tmp_path / "results/demo/results.sqlite") as db:
        rows = db.execute("SELECT case_id, status FROM cases").fetchall()
    assert {case for case, _ in rows} <= finished and {status for _, status in rows} == {"ok"}
    time.sleep(1.0)  # > FAKE_SLEEP: the orphaned cases got SIGTERM (parent-death signal) and wrote nothing
    assert set(results_of(path)) == finished

    assert subprocess.run(command + ["--quiet"], env=env, capture_output=True).returncode == 0
    counts = fake()
    assert len(results_of(path)) == 20 and set(counts) == set(results_of(path))
    assert all(counts[case] == 1 for case in finished)
    assert interrupted and all(counts[case] == 2 for case in interrupted)  # killed mid-run, so run again
    with sqlite3.connect(tmp_path / "results/demo/results.sqlite") as db:
        assert db.execute("SELECT count(*), count(DISTINCT case_id) FROM cases").fetchone() == (20, 20)


def test_two_cases_on_two_mpi_ranks(tmp_path, fake, monkeypatch):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2] }',
                      launcher=f"mpirun -n {{ranks}} {FAKE}", settings="ranks_per_case = 2")
    path.write_text(path.read_text().replace("jobs = 2", "jobs = 1"))
    for name, value in (("OMPI_ALLOW_RUN_AS_ROOT", "1"), ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
                        ("OMPI_MCA_rmaps_base_oversubscribe", "1"), ("FAKE_RANKS", "2")):
        monkeypatch.setenv(name, value)
    assert run_study(path) == 0
    results = results_of(path)
    assert len(results) == 2 and {r["info"]["ranks"] for r in results.values()} == {2}
    rows = Database(tmp_path / "results/demo/results.sqlite", ["contact.mu"]).rows()
    assert [row["ranks"] for row in rows] == [2, 2]


def test_real_rcc_cases_on_two_mpi_ranks(tmp_path, fake, monkeypatch):
    """End to end: the real `femcontact run` under a real `mpirun -n 2` (RCC cases: no FFCx, fast)."""
    for name, value in (("OMPI_ALLOW_RUN_AS_ROOT", "1"), ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
                        ("OMPI_MCA_rmaps_base_oversubscribe", "1")):
        monkeypatch.setenv(name, value)
    path = tmp_path / "rcc.toml"
    path.write_text(f'[study]\nname = "rcc"\nscene = "{HERE.parents[1] / "scenes/rcc.toml"}"\nranks_per_case = 2\n'
                    'jobs = 1\n[sweep]\ngrid = { "rcc.theta_l" = [60.0, 70.0] }\n')
    assert run_study(path) == 0
    rows = Database(tmp_path / "results/rcc/results.sqlite", ["rcc.theta_l"]).rows()
    assert [(row["rcc.theta_l"], row["status"], row["ranks"]) for row in rows] == [(60.0, "ok", 2), (70.0, "ok", 2)]
    assert all(isinstance(row["max_rel_error"], float) for row in rows)


def test_shared_prefix_runs_once_and_variants_restart_from_it(tmp_path, fake):
    path = make_study(tmp_path, '[sweep]\ngrid = { "steps.1.force" = [[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]] }',
                      settings="shared_steps = 1")
    assert run_study(path) == 0
    prefix_dirs = list((tmp_path / "results/demo/prefix").iterdir())
    assert len(prefix_dirs) == 1 and (prefix_dirs[0] / "checkpoint/state").exists()
    calls = {p.name.split(".")[0]: p.read_text() for p in (tmp_path / "calls").iterdir()}
    assert "--checkpoint" in calls.pop(prefix_dirs[0].name)
    assert len(calls) == 3 and all(f"--restart {prefix_dirs[0].resolve()}/checkpoint" in a for a in calls.values())



def test_a_filmed_case_shares_the_prefix_of_the_others(tmp_path):
    """Output settings (a time series for the report's film) do not change the shared steps' physics."""
    from femcontact.study.study_file import load_study

    path = make_study(tmp_path, '[sweep]\ngrid = { "steps.1.force" = [[1.0, 0.0], [2.0, 0.0]] }\n'
                      '[animation]\nselect = [ { "steps.1.force" = [2.0, 0.0] } ]', settings="shared_steps = 1")
    study = load_study(path, results_root=tmp_path / "results")
    filmed = [case for case in study.cases if case.scene["outputs"]["fields"]]
    assert len(filmed) == 1 and len({case.prefix.id for case in study.cases}) == 1


# -- report ---------------------------------------------------------------------------------------

class Page(HTMLParser):
    """The table headers, body rows and image sources of an index.html."""

    def __init__(self):
        super().__init__()
        self.headers, self.rows, self.images, self.cell = [], [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag in ("th", "td"):
            self.cell = ""
        elif tag == "img":
            self.images.append(dict(attrs)["src"])

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data

    def handle_endtag(self, tag):
        if tag in ("th", "td"):
            (self.headers if tag == "th" else self.rows[-1]).append(self.cell)
            self.cell = None


def test_report_writes_plots_summary_html_and_snapshots(tmp_path, fake, monkeypatch, capsys):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2], "contact.gamma" = [1.0, 2.0] }\n'
                                '[[plot]]\nx = "contact.mu"\ny = "product"\nseries = "contact.gamma"\n'
                                '[[plot]]\nx = "contact.gamma"\ny = "time.total"\nkind = "scatter"\n'
                                'logy = true\nfile = "timing.png"\n'
                                '[snapshots]\nselect = [ { "contact.mu" = 0.1, "contact.gamma" = 2.0 } ]\n'
                                'zoom = "contact_A"\n'
                                '[report]\ncolumns = ["case_id", "contact.mu", "contact.gamma", "status", "product", '
                                '"time.total"]')
    monkeypatch.setenv("FAKE_FIELDS", "2")
    assert run_study(path) == 0
    assert main(["report", str(path), "--results", str(tmp_path / "results")]) == 0
    out = capsys.readouterr().out
    results = tmp_path / "results/demo"
    pictures = [results / "product_vs_contact.mu.png", results / "timing.png",
                *(results / "snapshots").iterdir()]
    assert len(pictures) == 3 and all(p.read_bytes()[:8] == PNG and str(p) in out for p in pictures)
    summary = (results / "summary.md").read_text()
    assert "4 cases: 4 ok" in summary and summary.count("| ok |") == 4
    # the answer first (the metric), then the inputs, then the run's columns, each group as declared
    headers = ["product", "friction mu", "Nitsche gamma", "case", "status", "time total (s)"]
    assert "| " + " | ".join(headers) + " |" in summary.splitlines()

    page = Page()
    page.feed((results / "index.html").read_text())
    assert page.headers == headers and len(page.rows) == 1 + 4 and all(len(r) == 6 for r in page.rows[1:])
    by_mu_gamma = {(float(r[1]), float(r[2])): float(r[0]) for r in page.rows[1:]}
    assert by_mu_gamma == pytest.approx({(0.1, 1.0): 0.1, (0.1, 2.0): 0.2, (0.2, 1.0): 0.2, (0.2, 2.0): 0.4})
    assert sorted(results / src for src in page.images) == sorted(pictures)
    assert sorted(page.images) == sorted(re.findall(r"!\[[^]]*\]\(([^)]+)\)", summary))


def test_report_columns_default_and_checked(tmp_path, fake, capsys):
    sweep = '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2], "contact.gamma" = [1.0, 2.0] }\n'
    path = make_study(tmp_path, sweep)
    assert run_study(path) == 0
    assert main(["report", str(path), "--results", str(tmp_path / "results")]) == 0
    summary = (tmp_path / "results/demo/summary.md").read_text().splitlines()
    header = next(line for line in summary if line.startswith("| friction mu |"))
    assert header == "| friction mu | Nitsche gamma | status | case | wall time (s) |"

    path.write_text(path.read_text() + '[report]\ncolumns = ["contact.mu", "prodcut"]\n')
    assert main(["report", str(path), "--results", str(tmp_path / "results")]) == 2
    assert "[report] columns: 'prodcut' is neither a column of results.csv nor a scene key" in capsys.readouterr().err
    path.write_text(path.read_text().replace('"prodcut"', '"contact.theta"'))  # a scene key that is not swept
    assert main(["report", str(path), "--results", str(tmp_path / "results")]) == 0
    path.write_text(path.read_text().replace('"contact.theta"', '"contact.mu"'))
    with pytest.raises(InputError, match="report.columns = .*column 'contact.mu' is empty or repeated"):
        load_study(path)
    make_study(tmp_path, sweep + "[report]\ncolumns = [" + ", ".join(f'"c{i}"' for i in range(26)) + "]\n")
    with pytest.raises(InputError, match="26 columns, at most 25"):
        load_study(path)


def test_plot_lines_join_only_cases_differing_in_x():
    from femcontact.study.report import curves

    def row(a, b, c):
        return {"case_id": f"{a}-{b}-{c}", "status": "ok", "scene": {}, "a": a, "b": b, "c": c, "y": a * b + c}

    rows = [row(a, 1.0, 1.0) for a in (1.0, 2.0, 3.0, 4.0)] + [row(a, 2.0, 1.0) for a in (1.0, 2.0)] + \
        [row(3.0, 1.0, 2.0)] + [row(a, 2.0, 2.0) for a in (2.0, 1.0)] + [{**row(5.0, 1.0, 1.0), "status": "failed"}]
    spec = {"x": "a", "y": "y", "series": "", "kind": "line"}
    lines = curves(spec, rows, ["a", "b", "c"])
    assert [line["label"] for line in lines] == ["reference: b = 1; c = 1", "c = 2", "b = 2", "b = 2; c = 2"]
    assert [line["joined"] for line in lines] == [True, False, True, True]
    assert lines[0]["reference"] and not any(line["reference"] for line in lines[1:])
    for line in lines:  # every curve is one (b, c): y - a b is constant along it, and x increases
        b = 2.0 if "b = 2" in line["label"] else 1.0
        assert len({y - a * b for a, y in line["points"]}) == 1
        assert [a for a, _ in line["points"]] == sorted(a for a, _ in line["points"])
    assert sum(len(line["points"]) for line in lines) == 9  # the failed case is left out
    scatter = curves({**spec, "kind": "scatter", "series": "b"}, rows, ["a", "b", "c"])
    assert [(line["label"], len(line["points"]), line["joined"]) for line in scatter] == \
        [("reference: b = 1", 5, False), ("b = 2", 4, False)]
    assert curves(spec, [], ["a", "b", "c"]) == []  # nothing run yet
    grid = [row(a, b, 1.0) for a in (1.0, 2.0) for b in (10.0, 2.0)]  # a full grid: no value is the most common
    assert [(line["label"], line["reference"], line["joined"]) for line in curves(spec, grid, ["a", "b", "c"])] == \
        [("b = 2", False, True), ("b = 10", False, True)]


def _dark_blue_share(png) -> float:
    """Share of the coloured pixels (not white, grey or black) in jet's lowest colour (0, 0, 0.5)."""
    import matplotlib.pyplot as plt

    rgb = plt.imread(png)[..., :3]
    coloured = rgb.max(axis=-1) - rgb.min(axis=-1) > 0.25
    bottom = (rgb[..., 0] < 0.1) & (rgb[..., 1] < 0.1) & (rgb[..., 2] > 0.3) & (rgb[..., 2] < 0.6)  # 3-D: lit
    return float((bottom & coloured).sum() / coloured.sum())


@pytest.mark.parametrize("dim, cellwise", [(2, False), (3, True)])
def test_snapshot_colour_range_clips_a_singular_peak(tmp_path, dim, cellwise):
    from synthetic_fields import write_fields

    from femcontact.outputs.snapshot import render

    von_mises = write_fields(tmp_path / "fields.npz", dim, cellwise, singular=True)
    info = render(tmp_path / "fields.npz", tmp_path / "s.png", zoom="contact_A")
    with np.load(tmp_path / "fields.npz") as fields:
        cells, n_points = fields["cells"], len(fields["points"])
    # the structured mesh's cells all have one size: a node's share of the body is proportional to
    # its number of cells, a cell's share is one
    share = np.bincount(cells.ravel(), minlength=n_points).astype(float) if not cellwise else np.ones(len(cells))
    low, high = info["ranges"][0]
    assert low == pytest.approx(von_mises.min(), rel=1e-12)
    assert share[von_mises > high].sum() <= 0.01 * share.sum() < share[von_mises >= high].sum()
    assert high < 0.01 * von_mises.max()  # the peak of 1e4 (or its cell mean) is far outside the range
    assert info["peak"]["value"] == von_mises.max() and info["peak"]["near"] == "contact_A"
    assert info["peak"]["distance"] == pytest.approx(0.0 if not cellwise else 0.3, abs=0.3)
    assert (tmp_path / "s.png").read_bytes()[:8] == PNG
    render(tmp_path / "fields.npz", tmp_path / "body.png")
    with pytest.raises(ValueError, match="radius"):  # [x, y, r] read as x, r: a slip a user makes
        render(tmp_path / "fields.npz", tmp_path / "bad.png", zoom=(20.0, -5.4))
    shown = _dark_blue_share(tmp_path / "body.png")
    render(tmp_path / "fields.npz", tmp_path / "full.png", percentile=100.0)
    unclipped = _dark_blue_share(tmp_path / "full.png")
    print(f"\nshare of the picture in the lowest colour: {shown:.2f} clipped, {unclipped:.2f} min..max")
    if dim == 2:  # exact colours (no lighting): nearly all of the body in the lowest colour without clipping
        assert unclipped > 0.8 and shown < 0.2
    else:  # lit faces: the shading blurs the colour classes
        assert shown < unclipped - 0.2


def test_offscreen_snapshot_prints_no_display_warning(tmp_path):
    from synthetic_fields import write_fields

    write_fields(tmp_path / "fields.npz", 2)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    done = subprocess.run([sys.executable, "-c", "import sys; from femcontact.outputs.snapshot import render; "
                           "render(sys.argv[1], sys.argv[2])", str(tmp_path / "fields.npz"), str(tmp_path / "s.png")],
                          env=env, capture_output=True, text=True)
    assert done.returncode == 0 and (tmp_path / "s.png").exists(), done.stderr
    assert done.stderr == "" and done.stdout == ""


# -- large sweeps, one error for all, --status of a local run ---------------------------------------

def test_a_large_sweep_is_counted_first_refused_past_the_limit_and_made_lazily(tmp_path, capsys, fake,
                                                                              monkeypatch):
    keys = ("contact.mu", "contact.gamma", "materials.block.E", "materials.block.nu", "mesh.resolution")
    grid = ", ".join(f'"{key}" = [{", ".join(f"{0.1 + i / 100:.2f}" for i in range(10))}]' for key in keys)
    path = make_study(tmp_path, f"[sweep]\ngrid = {{ {grid} }}\n")
    results = tmp_path / "results"
    start = time.perf_counter()
    code = main(["study", str(path), "--results", str(results)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "the sweep makes 100000 cases, more than the limit of 10000; nothing was run (pass --max-cases 100000" in err
    assert time.perf_counter() - start < 5  # refused before the cases are made (making them: ~1 min)
    assert not results.exists() and fake() == {}
    # the cases are made one at a time: the first arrive after as many resolutions, not 100000
    import femcontact.study.study_file as study_file

    resolved = []
    monkeypatch.setattr(study_file, "resolve_scene", lambda data: resolved.append(1) or resolve_scene(data))
    study = load_study(path, results_root=results, resolve_cases=False)
    assert study.count == 100000 and study.cases == []
    cases = study_file.iter_cases(study)
    first = [next(cases) for _ in range(3)]
    assert [case.params["mesh.resolution"] for case in first] == [0.1, 0.11, 0.12] and len(resolved) <= 5
    monkeypatch.undo()
    # a small sweep: --max-cases below its size refuses it, --list states the count, then the cases
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3] }\n')
    assert main(["study", str(path), "--results", str(results), "--max-cases", "2"]) == 2
    assert "makes 3 cases, more than the limit of 2" in capsys.readouterr().err
    monkeypatch.setattr("femcontact.study.command.ANNOUNCED_CASES", 3)
    assert main(["study", str(path), "--results", str(results), "--list"]) == 0
    out, err = capsys.readouterr()
    assert err == "study demo: 3 cases in the sweep\n" and len(out.splitlines()) == 3 and "contact.mu=0.3" in out


def test_a_scene_invalid_whatever_the_sweep_sets_is_one_error(tmp_path, capsys, fake):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3], "contact.gamma" = [1.0, 2.0] }\n')
    code = main(["study", str(path), "--results", str(tmp_path / "results"), "--set", "materials.block.E=-1"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "6 invalid case(s), nothing was run: materials.block.E = -1: out of range, expected a number > 0 " \
           "(the scene base.toml with the study's values, whatever the sweep sets)" in err
    # an error the sweep causes is said once, with the cases it concerns
    code = main(["study", str(path), "--results", str(tmp_path / "results"), "--set", "contact.theta=0.5"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("contact.theta = 0.5") == 1 and fake() == {}


def test_status_during_a_local_run_shows_running_and_queued_cases(tmp_path, capsys, fake, monkeypatch):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3] }\n', settings="jobs = 1")
    path.write_text(path.read_text().replace("jobs = 2\n", ""))
    results = tmp_path / "results"
    monkeypatch.setenv("FAKE_HANG_MU", "0.1")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    study = subprocess.Popen([sys.executable, "-m", "femcontact", "study", str(path), "--results", str(results),
                              "--quiet"], env=env, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60
        while not fake() and time.monotonic() < deadline:  # the first case has started
            time.sleep(0.05)
        assert main(["study", str(path), "--results", str(results), "--status"]) == 0
        out = capsys.readouterr().out
        assert out.splitlines()[-1].endswith("3 cases: 0 done, 0 without equilibrium, 0 failed, 1 running, 2 queued, 0 missing"), out
        assert re.search(r"running\s+contact.mu=0.1", out)
    finally:
        study.terminate()
        study.communicate(timeout=30)
    assert main(["study", str(path), "--results", str(results), "--status"]) == 0  # nobody runs it now
    assert capsys.readouterr().out.splitlines()[-1].endswith("0 running, 0 queued, 3 missing")


def test_a_case_without_equilibrium_is_an_answer_counted_apart_and_not_retried(tmp_path, fake, monkeypatch, capsys):
    path = make_study(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3] }')
    monkeypatch.setenv("FAKE_NO_EQUILIBRIUM_MU", "0.1")
    monkeypatch.setenv("FAKE_FAIL_MU", "0.2")
    assert run_study(path) == 1  # one failed
    out = capsys.readouterr().out
    assert "3 cases, 1 ok, 1 without equilibrium, 1 failed" in out
    assert re.search(r"no equilibrium \w+ contact.mu=0.1: step 'press': the load needs mu >= 0.5", out)
    before = fake()
    assert run_study(path, "--retry-failed") == 1
    again = fake()
    assert sum(again.values()) == sum(before.values()) + 1  # only the failed case ran again
    monkeypatch.delenv("FAKE_FAIL_MU")
    assert run_study(path, "--retry-failed") == 0  # an answer and two ok: nothing failed
    assert main(["study", str(path), "--results", str(tmp_path / "results"), "--status"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].endswith("3 cases: 2 done, 1 without equilibrium, 0 failed, "
                                                             "0 running, 0 queued, 0 missing")
    assert main(["report", str(path), "--results", str(tmp_path / "results")]) == 0
    summary = (tmp_path / "results/demo/summary.md").read_text()
    assert "3 cases: 2 ok, 1 without a static equilibrium of their load, 0 failed" in summary
    with sqlite3.connect(tmp_path / "results/demo/results.sqlite") as db:
        assert sorted(s for (s,) in db.execute("SELECT status FROM cases")) == ["no_equilibrium", "ok", "ok"]
