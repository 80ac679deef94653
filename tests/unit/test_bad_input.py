"""Bad input and faults: every bad value is refused before anything runs, with exit
code 2 and one message naming the key or the file, no traceback and nothing written; a
read-only or full results directory ends with one message, no temporary files and a
database that agrees with the case directories.

The CLI runs in-process (`femcontact.cli.main`). Read-only and full file systems are real:
small tmpfs mounts (root; skipped where mounting is not allowed) or, for read-only without
root, a chmod 555 directory. Studies run through tests/support/fake_case.py (no solver).
"""
import contextlib
import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from femcontact.cli import main
from block_scene import BLOCK_SCENE

HERE = Path(__file__).parent
SUPPORT = HERE.parent / "support"
SCENES = HERE.parents[1] / "scenes"
WEDGING = str(SCENES / "wedging_2d.toml")
RCC = str(SCENES / "rcc.toml")
FAKE = f"{sys.executable} {SUPPORT / 'fake_case.py'}"
BLOCK = BLOCK_SCENE


def cli(capsys, *argv) -> tuple[int, str]:
    """Exit code and stderr of `femcontact ARGV` (argparse errors exit through SystemExit)."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit_:
        code = exit_.code
    return code, capsys.readouterr().err


def assert_refused(code: int, err: str, *fragments: str) -> None:
    """Exit 2, one error message containing every fragment, no traceback."""
    assert code == 2, err
    assert "Traceback" not in err and err.count("error:") == 1, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


def sets(*assignments) -> list[str]:
    return [arg for assignment in assignments for arg in ("--set", assignment)]


# -- scene values: each refused by `femcontact run` before the output directory exists --------------

RUN_CASES = [
    # values that would hang gmsh or crash it without these checks
    (["hole.block_width=inf"], ["hole.block_width = inf: not a finite number"]),
    (["hole.depth=inf"], ["hole.depth = inf: not a finite number"]),
    (["mesh.resolution=1e4"], ["mesh too large", "mesh.resolution = 10000"]),
    # the element-count guard and its floor
    (["mesh.contact_size=1e-7"], ["mesh too large", "mesh.contact_size"]),
    (["hole.block_width=1e6"], ["mesh too large", "hole.block_width = 1e+06"]),
    (["mesh.resolution=0.01"], ["mesh too coarse", "mesh.resolution = 0.01"]),
    (["mesh.resolution=1e300"], ["mesh too large: about inf elements"]),
    # NaN and infinity, key by key
    (["contact.mu=nan"], ["contact.mu = nan: not a finite number"]),
    (["materials.hole.density=nan"], ["materials.hole.density = nan"]),
    (["materials.hole.nu=nan"], ["materials.hole.nu = nan"]),
    (["materials.hole.E=inf"], ["materials.hole.E = inf"]),
    (["materials.hole.yield_stress=nan"], ["materials.hole.yield_stress = nan"]),
    (["peg.insertion_depth=nan"], ["peg.insertion_depth = nan"]),
    (["peg.placement='centred'", "peg.tilt=nan"], ["peg.tilt = nan"]),
    (["peg.gap=inf"], ["peg.gap = inf"]),
    (["peg.width=nan"], ["peg.width = nan"]),
    (["peg.chamfer_angle=nan"], ["peg.chamfer_angle = nan"]),
    (["hole.width=inf"], ["hole.width = inf"]),
    (["contact.gamma=inf"], ["contact.gamma = inf"]),
    (["contact.gamma_t=nan"], ["contact.gamma_t = nan"]),
    (["mesh.contact_size=nan"], ["mesh.contact_size = nan"]),
    (["mesh.size_max=inf"], ["mesh.size_max = inf"]),
    (["mesh.contact_zone=nan"], ["mesh.contact_zone = nan"]),
    (["steps.0.force=[nan, 1.0]"], ["steps[0].force = [nan, 1.0]: not a finite number"]),
    (["steps.0.force=[-5.0, inf]"], ["steps[0].force = [-5.0, inf]"]),
    (["steps.0.moment=[nan]"], ["steps[0].moment = [nan]"]),
    (["steps.0.duration=inf"], ["steps[0].duration = inf"]),
    (["steps.0.pulse.frequency=inf"], ["steps[0].pulse.frequency = inf"]),
    (["rigid_body.dofs.x='prescribed'", "steps.0.motion.x=nan"], ["steps[0].motion.x = nan"]),
    (["rigid_body.mass=nan"], ["rigid_body.mass = nan"]),
    (["dynamics.gravity=inf"], ["dynamics.gravity = inf"]),
    (["dynamics.newmark_beta=nan"], ["dynamics.newmark_beta = nan"]),
    (["solver.rtol=nan"], ["solver.rtol = nan"]),
    (["solver.atol=inf"], ["solver.atol = inf"]),
    # errors that used to surface only while running
    (["steps.0.load_point='nowhere'"], ["steps[0].load_point = 'nowhere': unknown point", "peg_top"]),
    (["steps=[]"], ["steps = []"]),
    (["steps.1.name='load'"], ["steps[1].name = 'load': also the name of steps[0]"]),
    (["solver.petsc_options={ksp_type='cgg'}"], ["solver.petsc_options.ksp_type = 'cgg': names no KSP type"]),
    (["solver.petsc_options={pc_type='lux'}"], ["solver.petsc_options.pc_type = 'lux': names no PC type"]),
    (["solver.petsc_options={pc_factor_mat_solver_type='mumsp'}"],
     ["solver.petsc_options.pc_factor_mat_solver_type = 'mumsp'"]),
    (["solver.petsc_options={pc_factor_mat_solver_type='mkl_pardiso'}"], ["mkl_pardiso': this PETSc cannot"]),
    (["solver.petsc_options={kps_type='cg'}"], ["solver.petsc_options.kps_type: not a linear-solver option"]),
    (["solver.petsc_options={ksp_rtol=nan}"], ["solver.petsc_options.ksp_rtol = nan: not a finite number"]),
    (["solver.petsc_options=3"], ["solver.petsc_options = 3: must be a table"]),
    # limits: a day of solves and gigabytes of history are refused, not started
    (["steps.0.increments=10000000"], ["steps[0].increments = 10000000", "10000005 increments in all, at most 100000"]),
    (["steps.0.increments=60000", "steps.1.increments=60000"],
     ["steps[0].increments = 60000, steps[1].increments = 60000: 120000 increments in all"]),
    (["effects=['plasticity', 'large_strain']"], ["'plasticity' is small-strain"]),
    (["plasticity.hardening=[[0, 210], [1, 200]]"], ["plasticity.hardening = [[0, 210], [1, 200]]", "no softening"]),
    (["plasticity.hardening=[[0.1, 210]]"], ["plasticity.hardening", "start at 0"]),
    (["plasticity.hardening=[[0, 210, 1]]"], ["plasticity.hardening", "[[plastic strain, yield stress (MPa)], ...]"]),
    (["plasticity.hardening=[[0, nan]]"], ["plasticity.hardening", "finite"]),
    (["plasticity.hardening_modulus=-1"], ["plasticity.hardening_modulus = -1"]),
    (["effects=['plasticity']", "plasticity.hardening=[[0, 200], [1, 290]]"],
     ["plasticity.hardening = [[0, 200], [1, 290]]: its first yield stress must be materials.hole.yield_stress = 210"]),
]


@pytest.mark.parametrize("assignments, fragments", RUN_CASES, ids=[" ".join(a) for a, _ in RUN_CASES])
def test_run_refuses_bad_scene_values(tmp_path, capsys, assignments, fragments):
    out = tmp_path / "out"
    code, err = cli(capsys, "run", WEDGING, *sets(*assignments), "--out", out)
    assert_refused(code, err, "wedging_2d.toml", *fragments)
    assert not out.exists()


INSERTION = str(SCENES / "insertion_2d.toml")
DISLODGING = str(SCENES / "dislodging_2d.toml")


@pytest.mark.parametrize("scene, assignments, fragment", [
    (INSERTION, ["support.model='matrix'"], "support.stiffness = []: 0 values, expected 9 (3x3, row by row)"),
    (INSERTION, ["support.model='matrix'", "support.stiffness=[1.0, 2.0]"], "support.stiffness = [1.0, 2.0]: 2 values"),
    (INSERTION, ["support.model='matrix'", "support.stiffness=[-1, 0, 0, 0, -1, 0, 0, 0, -1]"],
     "not positive definite (smallest eigenvalue -1)"),
    (INSERTION, ["support.model='matrix'", "support.stiffness=[10, 20, 0, 20, 10, 0, 0, 0, 1]"],
     "not positive definite (smallest eigenvalue -10)"),  # positive diagonal, eigenvalues 30, -10, 1
    (INSERTION, ["support.model='matrix'", "support.stiffness=[10, 1, 0, 0, 10, 0, 0, 0, 1]"], "must be symmetric"),
    (INSERTION, ["support.stiffness=[1.0, 2.0]"],
     "support.stiffness = [1.0, 2.0]: read only with support.model = 'matrix' (support.model = 'springs')"),
    (DISLODGING, ["steps.2.increments=10000000"], "steps[2].increments = 10000000: 10000215 increments in all"),
    (DISLODGING, ["dislodging.rotation='spring'"], "dislodging.rotation_stiffness = 0: a gripper spring needs "
                                                   "rotation = 'spring' and a stiffness > 0 (rotation = 'spring')"),
    (DISLODGING, ["dislodging.rotation_stiffness=1e5"], "dislodging.rotation_stiffness = 100000: a gripper spring"),
    (DISLODGING, ["dislodging.rotation='spring'", "dislodging.rotation_stiffness=-1"], "dislodging.rotation_stiffness = -1"),
    (INSERTION, ["contact.surface='exact'"], "contact.surface = 'exact': for the round hole of a 3-D peg_in_hole "
                                             "scene with a rigid peg (dim = 2"),
    (INSERTION, ["contact.surface='round'"], "contact.surface = 'round'"),
    (INSERTION, ["mesh.geometry_order=2"], "mesh.geometry_order = 2: curved elements need a displacement of the "
                                           "same degree (mesh.degree = 1; set it to 2)"),
    (INSERTION, ["mesh.geometry_order=3"], "mesh.geometry_order = 3"),
], ids=["matrix without stiffness", "stiffness of 2 values", "negative stiffness", "indefinite stiffness",
        "asymmetric stiffness", "stiffness without the matrix model", "dislodging increments",
        "gripper spring without stiffness", "gripper stiffness without the spring", "negative gripper stiffness",
        "exact surface in 2-D", "unknown contact surface", "curved elements at P1", "cubic geometry"])
def test_run_refuses_bad_support_matrices_and_huge_increments(tmp_path, capsys, scene, assignments, fragment):
    out = tmp_path / "out"
    assert_refused(*cli(capsys, "run", scene, *sets(*assignments), "--out", out), Path(scene).name, fragment)
    assert not out.exists()


def test_a_positive_definite_support_matrix_is_the_springs_it_spells(tmp_path):
    """The 'matrix' model with the springs' diagonal is the springs' support (the same K)."""
    from femcontact.families import load_scene
    from femcontact.effects.compliant_support import stiffness_matrix

    springs = load_scene(INSERTION)
    matrix = load_scene(INSERTION, ["support.model='matrix'", "support.stiffness=[20, 0, 0, 0, 1e5, 0, 0, 0, 3000]"])
    assert np.array_equal(stiffness_matrix(matrix), stiffness_matrix(springs))


def test_a_stop_column_that_names_no_history_column_is_refused_before_solving(tmp_path, capsys):
    """Known once the model is built: refused then, in one line listing the columns, before the
    first increment, and the case directory it made is removed."""
    out = tmp_path / "out"
    code, err = cli(capsys, "run", INSERTION, *sets("mesh.resolution=0.5", "steps.0.stop.column='support_Fyy'"),
                    "--out", out, "--quiet")
    assert_refused(code, err, "insertion_2d.toml: steps[0].stop.column = 'support_Fyy': no such history column",
                   "support_Fy, ")
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


RCC_CASES = [
    (["motion.about_z=nan"], "motion.about_z = nan"),
    (["rcc.k=inf"], "rcc.k = inf"),
    (["rcc.theta_l=nan"], "rcc.theta_l = nan"),
    (["centre.axial_load=nan"], "centre.axial_load = nan"),
    (["motion.translation=inf"], "motion.translation = inf"),
]


@pytest.mark.parametrize("assignments, fragment", RCC_CASES, ids=[a[0] for a, _ in RCC_CASES])
def test_rcc_scene_refuses_non_finite_values(tmp_path, capsys, assignments, fragment):
    out = tmp_path / "out"
    assert_refused(*cli(capsys, "run", RCC, *sets(*assignments), "--out", out), fragment + ": not a finite number")
    assert not out.exists()


RCC_CLI = ["--b", "50", "--peg-length", "50", "--theta-l", "70", "--k", "200"]


@pytest.mark.parametrize("change, fragment", [
    (("--k", "inf"), "k = inf: must be a finite number"),
    (("--k", "nan"), "k = nan: must be a finite number"),
    (("--b", "inf"), "b = inf: must be a finite number"),
    (("--theta-l", "nan"), "theta_L = nan: must be a finite number"),
    (("--peg-length", "nan"), "peg length L = nan: must be a finite number"),
    (("--offset-t", "inf"), "offset T = inf: must be a finite number"),
    (("--about-z", "nan"), "--about-z nan: must be a finite number"),
    (("--move", "ry=nan"), "--move 'ry=nan': the value must be finite"),
], ids=lambda v: " ".join(v) if isinstance(v, tuple) else None)
def test_rcc_command_refuses_non_finite_numbers(capsys, change, fragment):
    args = dict(zip(RCC_CLI[::2], RCC_CLI[1::2]))
    args[change[0]] = change[1]
    argv = [arg for item in args.items() for arg in item]
    moves = [] if change[0] == "--move" else ["--move", "rx=0.05"]
    assert_refused(*cli(capsys, "rcc", "wrench", *argv, *moves), fragment)


def test_rcc_displace_refuses_an_infinite_load(capsys):
    assert_refused(*cli(capsys, "rcc", "displace", *RCC_CLI, "--load", "Fx=inf"), "--load 'Fx=inf'")


def test_run_refuses_checkpoint_requests_that_cannot_work(tmp_path, capsys):
    out = tmp_path / "out"
    assert_refused(*cli(capsys, "run", RCC, "--checkpoint", "--out", out), "--checkpoint/--restart")
    missing = tmp_path / "nowhere"
    assert_refused(*cli(capsys, "run", WEDGING, "--restart", missing, "--out", out), f"--restart {missing}")
    assert not out.exists()


def test_bad_input_under_mpirun_is_one_message(tmp_path, capsys, monkeypatch):
    """Every rank finds the error; only rank 0 of the launch prints it."""
    monkeypatch.setenv("OMPI_COMM_WORLD_RANK", "1")
    assert cli(capsys, "run", WEDGING, *sets("contact.mu=nan"), "--out", tmp_path / "o") == (2, "")
    monkeypatch.setenv("OMPI_COMM_WORLD_RANK", "0")
    assert_refused(*cli(capsys, "run", WEDGING, *sets("contact.mu=nan"), "--out", tmp_path / "o"), "contact.mu")


def test_run_refuses_a_malformed_override(tmp_path, capsys):
    assert_refused(*cli(capsys, "run", WEDGING, "--set", "peg.insertion_depth", "--out", tmp_path / "o"),
                   "expected KEY=VALUE")


# -- files -----------------------------------------------------------------------------------------

def test_unreadable_scene_files(tmp_path, capsys):
    latin = tmp_path / "latin.toml"
    latin.write_bytes("name = 'Übergang'\n".encode("latin-1"))
    broken = tmp_path / "broken.toml"
    broken.write_text("[peg\nwidth = 1\n")
    for path, fragment in ((latin, "not a UTF-8 text file"), (tmp_path, "a directory, expected a TOML file"),
                           (tmp_path / "missing.toml", "no such file"), (broken, "not valid TOML")):
        out = tmp_path / "out"
        assert_refused(*cli(capsys, "run", path, "--out", out), str(path), fragment)
        assert not out.exists()


def study_file(tmp_path, body: str, base: str = BLOCK, settings: str = "") -> Path:
    (tmp_path / "base.toml").write_text(base)
    path = tmp_path / "demo.toml"
    path.write_text(f'[study]\nname = "demo"\nscene = "base.toml"\njobs = 2\nlauncher = "{FAKE} -n {{ranks}}"\n'
                    f"{settings}\n{body}")
    return path


STUDY_CASES = [
    ('[sweep]\ngrid = { "contact.mu" = [0.1, nan] }', "contact.mu = nan: not a finite number"),
    ('[sweep]\nzip = { "contact.gamma" = [1.0, inf] }', "contact.gamma = inf"),
    ('[sweep]\ngrid = { "steps.0.force" = [[0.0, nan]] }', "steps[0].force = [0.0, nan]"),
    ('[sweep]\ngrid = { "steps.0.load_point" = ["indenter", "peg_top"] }',
     "steps[0].load_point = 'peg_top': unknown point"),
    ('[sweep]\ngrid = { "solver.petsc_options.ksp_type" = ["preonly", "cgg"] }',
     "solver.petsc_options.ksp_type = 'cgg'"),
    ('[scene]\nsteps = [{ name = "a" }, { name = "a" }]', "steps[1].name = 'a'"),
    ('[scene]\nsteps = []', "steps = []"),
    ('[sweep]\ngrid = { "mesh.resolution" = [1.0, 1e4] }', "mesh too large"),
]


@pytest.mark.parametrize("body, fragment", STUDY_CASES, ids=[b.split("\n")[1] for b, _ in STUDY_CASES])
def test_study_prevalidation_refuses_every_bad_case(tmp_path, capsys, body, fragment):
    path = study_file(tmp_path, body)
    results = tmp_path / "results"
    assert_refused(*cli(capsys, "study", path, "--results", results), "invalid case", fragment, "nothing was run")
    assert not results.exists()


def test_study_refuses_bad_files_and_options(tmp_path, capsys):
    results = tmp_path / "results"
    path = study_file(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2] }')
    for option, fragment in ((("--ranks-per-case", "0"), "--ranks-per-case 0: expected >= 1"),
                             (("--jobs", "-1"), "--jobs -1: expected >= 0")):
        assert_refused(*cli(capsys, "study", path, *option, "--results", results), fragment)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(path.read_bytes().replace(b'"demo"', 'd\u00e9mo'.join('""').encode("latin-1")))
    assert_refused(*cli(capsys, "study", latin, "--results", results), str(latin), "not a UTF-8 text file")
    assert_refused(*cli(capsys, "study", tmp_path, "--results", results), "a directory, expected a TOML file")
    assert_refused(*cli(capsys, "report", tmp_path, "--results", results), "a directory, expected a TOML file")
    path.write_text(path.read_text().replace("base.toml", "gone.toml"))
    assert_refused(*cli(capsys, "study", path, "--results", results), "gone.toml: no such file")
    path = study_file(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1] }\n[snapshots]\nzoom = [20.0, -5.4, -1.0]')
    assert_refused(*cli(capsys, "study", path, "--results", results), "snapshots.zoom", "radius > 0")
    path = study_file(tmp_path, "", settings="time_limit = inf")
    assert_refused(*cli(capsys, "study", path, "--results", results), "study.time_limit = inf")
    for launcher, fragment in (("mpirn -n {ranks}", "'mpirn': no such program"),
                               ("mpirun -n {rank}", "KeyError: 'rank'"), ("mpirun '-n", "ValueError")):
        path = study_file(tmp_path, "")
        path.write_text(path.read_text().replace(f"{FAKE} -n {{ranks}}", launcher))
        assert_refused(*cli(capsys, "study", path, "--results", results), "study.launcher", fragment)
    assert not results.exists()


def test_rcc_study_prevalidation_refuses_nan(tmp_path, capsys):
    path = tmp_path / "rcc.toml"
    path.write_text(f'[study]\nname = "rcc"\nscene = "{RCC}"\n[sweep]\ngrid = {{ "motion.about_z" = [0.0, nan] }}\n')
    assert_refused(*cli(capsys, "study", path, "--results", tmp_path / "results"),
                   "motion.about_z = nan: not a finite number")
    assert not (tmp_path / "results").exists()


def test_outputs_that_are_files(tmp_path, capsys):
    occupied = tmp_path / "occupied"
    occupied.write_text("a file")
    assert_refused(*cli(capsys, "run", RCC, "--out", occupied), str(occupied), "cannot write (File exists)")
    path = study_file(tmp_path, "")
    assert_refused(*cli(capsys, "study", path, "--results", occupied), str(occupied / "demo"), "cannot write")
    assert occupied.read_text() == "a file"


# -- read-only and full results directories --------------------------------------------------------

@contextlib.contextmanager
def tmpfs(path: Path, size: str):
    """A tmpfs of `size` mounted at `path` (root only; skipped where mounting is refused)."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    path.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                             capture_output=True, text=True)
    if mounted.returncode:
        pytest.skip(f"cannot mount a tmpfs: {mounted.stderr.strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=True)


def remount(path: Path, options: str) -> None:
    subprocess.run(["mount", "-o", f"remount,{options}", str(path)], check=True)


@contextlib.contextmanager
def read_only(path: Path):
    """`path` made read-only: a read-only tmpfs remount as root, chmod 555 otherwise."""
    if os.geteuid() == 0:
        remount(path, "ro")
        try:
            yield
        finally:
            remount(path, "rw")
    else:
        path.chmod(0o555)
        try:
            yield
        finally:
            path.chmod(0o755)


@pytest.fixture
def disk(tmp_path):
    """A directory on its own small file system (tmpfs as root, else a plain directory)."""
    if os.geteuid() == 0:
        with tmpfs(tmp_path / "disk", "2m") as path:
            yield path
    else:
        (tmp_path / "disk").mkdir()
        yield tmp_path / "disk"


def temporaries(root: Path) -> list[Path]:
    return [p for p in root.rglob("*") if p.name.endswith(".tmp") or ".tmp." in p.name]


def consistent(results: Path) -> set[str]:
    """Check the study database against the case directories; returns the ids of finished cases."""
    done = {d.name for d in (results / "cases").iterdir() if (d / "result.json").exists()}
    with contextlib.closing(sqlite3.connect(results / "results.sqlite")) as db:
        assert db.execute("PRAGMA integrity_check").fetchone() == ("ok",)
        rows = {case for (case,) in db.execute("SELECT case_id FROM cases")}
    assert rows <= done
    for case in done:
        json.loads((results / "cases" / case / "result.json").read_text())  # whole, never truncated
    return done


def test_run_into_a_read_only_directory(disk, capsys):
    with read_only(disk):
        code, err = cli(capsys, "run", RCC, "--out", disk / "case")
    assert_refused(code, err, str(disk / "case"), "cannot write")
    assert not (disk / "case").exists()


def test_study_into_a_read_only_directory(disk, capsys):
    path = study_file(disk, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2, 0.3] }')
    results = disk / "results"
    with read_only(disk):
        assert_refused(*cli(capsys, "study", path, "--results", results, "--quiet"), str(results), "cannot write")
    assert not results.exists()
    assert cli(capsys, "study", path, "--results", results, "--quiet")[0] == 0
    capsys.readouterr()
    with read_only(disk):
        assert_refused(*cli(capsys, "study", path, "--results", results, "--quiet", "--force"), "cannot write")
        assert main(["study", str(path), "--results", str(results), "--list"]) == 0
        listing = capsys.readouterr()
        assert listing.out.count(" ok ") == 3 and listing.err == ""
        assert_refused(*cli(capsys, "report", path, "--results", results), str(results), "cannot write")
    assert len(consistent(results / "demo")) == 3 and not temporaries(disk)


def test_study_into_a_full_disk_stops_with_one_message_and_resumes(tmp_path, capsys):
    with tmpfs(tmp_path / "disk", "160k") as disk:
        path = study_file(disk, '[sweep]\ngrid = { "contact.mu" = [0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4], '
                                '"contact.gamma" = [1.0, 2.0, 3.0, 4.0, 5.0] }')
        results = disk / "results"
        code, err = cli(capsys, "study", path, "--results", results, "--quiet")
        assert_refused(code, err, "study demo: stopped after", "run the same command again")
        assert "No space left on device" in err or "database or disk is full" in err, err
        done = consistent(results / "demo")
        assert 0 < len(done) < 40 and not temporaries(disk)
        remount(disk, "size=16m")
        assert cli(capsys, "study", path, "--results", results, "--quiet")[0] == 0
        assert len(consistent(results / "demo")) == 40 and not temporaries(disk)


def test_run_on_a_full_disk_leaves_no_partial_file(tmp_path, capsys):
    with tmpfs(tmp_path / "disk", "64k") as disk:
        (disk / "case").mkdir()
        with contextlib.suppress(OSError), open(disk / "filler", "wb") as filler:
            filler.write(b"\0" * 200_000)
        code, err = cli(capsys, "run", RCC, "--out", disk / "case")
        assert_refused(code, err, str(disk / "case" / "scene.json"), "No space left on device")
        assert not any((disk / "case").iterdir())


def test_streamed_history_on_a_full_disk_keeps_whole_rows(tmp_path):
    from femcontact.io import WriteError
    from femcontact.outputs.history import HistoryWriter

    with tmpfs(tmp_path / "disk", "8k") as disk:
        history = HistoryWriter(disk / "history.csv")
        rows = [{"step": "load", "time": 0.1 * i, "force": np.pi * i} for i in range(1000)]  # ~40 kB
        for row in rows:
            history(row)
        history.close()
        assert isinstance(history.error, WriteError) and "No space left on device" in str(history.error)
        lines = (disk / "history.csv").read_text().splitlines(keepends=True)
        assert 10 < len(lines) < 1000 and all(line.endswith("\n") and line.count(",") == 2 for line in lines)


def test_write_atomic_keeps_the_old_file_and_no_temporary(tmp_path):
    from femcontact.io import WriteError, write_json_atomic, write_npz_atomic

    with tmpfs(tmp_path / "disk", "64k") as disk:
        target = disk / "fields.npz"
        target.write_bytes(b"old")
        big = np.random.default_rng(0).random(100_000)  # 800 kB, incompressible
        with pytest.raises(WriteError, match=r"fields.npz: cannot write \(No space left on device\)"):
            write_npz_atomic(target, values=big)
        assert target.read_bytes() == b"old" and [p.name for p in disk.iterdir()] == ["fields.npz"]
    write_json_atomic(tmp_path / "r.json", {"angle": float("nan"), "ratio": np.float64(np.inf), "n": np.int64(3)})
    assert json.loads((tmp_path / "r.json").read_text()) == {"angle": None, "ratio": None, "n": 3}


# -- the launcher's environment and errors ---------------------------------------------------------

def test_study_sets_what_open_mpi_needs(tmp_path, capsys, monkeypatch):
    """As root without OMPI_ALLOW_RUN_AS_ROOT (make sets it, a shell does not), mpirun refuses to start
    unless the runner sets it for its own launches."""
    for name in ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "OMPI_MCA_rmaps_base_oversubscribe"):
        monkeypatch.delenv(name, raising=False)
    path = study_file(tmp_path, '[sweep]\ngrid = { "contact.mu" = [0.1, 0.2] }')
    path.write_text(path.read_text().replace(f"{FAKE} -n {{ranks}}", f"mpirun -n {{ranks}} {FAKE}"))
    code, err = cli(capsys, "study", path, "--results", tmp_path / "results", "--quiet")
    assert code == 0, capsys.readouterr().out + err


def test_failed_launch_quotes_the_launchers_error(tmp_path, capsys):
    launcher = tmp_path / "launcher.py"
    launcher.write_text("print('-' * 74)\nprint('mpirun has detected an attempt to run as root.')\nprint()\n"
                        "print('You can override this protection by adding --allow-run-as-root')\n"
                        "print('-' * 74)\nraise SystemExit(1)\n")
    path = study_file(tmp_path, "")
    path.write_text(path.read_text().replace(f"{FAKE} -n {{ranks}}", f"{sys.executable} {launcher}"))
    assert cli(capsys, "study", path, "--results", tmp_path / "results", "--quiet")[0] == 1
    (case,) = (tmp_path / "results/demo/cases").iterdir()
    reason = json.loads((case / "result.json").read_text())["reason"]
    assert reason.startswith("exited with code 1 without a result; launcher: mpirun has detected an attempt to "
                             "run as root. You can override"), reason


# -- outputs ---------------------------------------------------------------------------------------

def released_wedge_metrics(contact_B: tuple, reactions: dict) -> dict:
    """`wedge_metrics` of the default 2-D wedging scene after a push of (-5, 1) N, released with
    contact B's centre at `contact_B` (None: no contact) and the support reactions `reactions`
    ({zone: (x, y)}, N)."""
    from types import SimpleNamespace

    from femcontact.families import load_scene
    from femcontact.families.wedging.metrics import wedge_metrics

    row = {"step": "release", "tilt_deg": 1.25, "applied_Fx": 0.0, "applied_Fy": 0.0, "stabilization_force": 0.0,
           "elastic_energy": 1e-3, "max_von_mises": 10.0, "contact_A_x": -20.0, "contact_A_y": -0.1,
           "contact_B_x": contact_B[0], "contact_B_y": contact_B[1]}
    for zone, (x, y) in reactions.items():
        row.update({f"reaction_support_{zone}_x": x, f"reaction_support_{zone}_y": y})
    loaded = {**row, "step": "load", "applied_Fx": -5.0, "applied_Fy": 1.0}
    problem = SimpleNamespace(model=SimpleNamespace(rigid={"tilt": 0.02}), deformable="hole",
                              support_dofs={"support_A": None, "support_B": None})
    return wedge_metrics(SimpleNamespace(scene=load_scene(WEDGING), history=[loaded, row], problem=problem,
                                         timings={"solve": 1.0}))


def test_wedge_angles_are_null_with_a_reason_when_contact_is_lost():
    """A released peg that has lost contact in zone B: the angles to the line of the contact points
    are undefined, reported as None (JSON null) with the reason, and the peg is not wedged."""
    metrics = released_wedge_metrics((None, None), {"A": (3.0, 0.1), "B": (-3.0, -0.1)})
    assert metrics["angle_A_deg"] is None and metrics["angle_B_deg"] is None
    assert metrics["angle_reason"].startswith("zone B has no contact after release")
    assert metrics["wedged"] is False and metrics["wedge_reason"] == "not collinear"


@pytest.mark.parametrize("residual", [1e-9, 4e-8])
def test_a_free_peg_has_no_balance_or_angles(residual):
    """A released peg whose residual reactions are round-off (below FORCE_FLOOR of the load) is not
    wedged, and its reactions' balance and angles, ratios of round-off, are undefined (None), not
    numbers that change between two runs."""
    metrics = released_wedge_metrics((20.0, -4.0), {"A": (residual, 0.3 * residual),
                                                    "B": (-0.7 * residual, 0.3 * residual)})
    assert metrics["residual_force_A"] == pytest.approx(residual * np.hypot(1.0, 0.3))
    assert metrics["imbalance"] is None and metrics["angle_A_deg"] is None and metrics["angle_B_deg"] is None
    assert metrics["angle_reason"].startswith("no residual force after release")
    assert metrics["wedged"] is False and metrics["wedge_reason"] == "no residual force"


def test_mesh_guard_survives_overflowing_sizes(tmp_path, capsys):
    """Sizes near the double-precision limit: refused or accepted, never an OverflowError."""
    scene = str(SCENES / "wedging_3d.toml")
    assert_refused(*cli(capsys, "run", scene, *sets("hole.block_width=1e300"), "--out", tmp_path / "o"),
                   "mesh too large", "hole.block_width = 1e+300")
    from femcontact.families import load_scene

    for overrides in (["mesh.size_max=1e300"], ["mesh.contact_zone=1e300", "mesh.resolution=0.5"]):
        load_scene(WEDGING, overrides)  # a coarse or an all-fine mesh of a 2-D body: allowed


def test_mesh_size_estimate_is_within_a_factor_of_three_of_gmsh():
    """The guard's element estimate against the count gmsh produces (2-D scenes, < 1 s each)."""
    import gmsh

    from femcontact.families import load_scene
    from geometry import gmsh_tools, mesh_size
    from geometry.model import builder

    for path, overrides in ((WEDGING, ["mesh.resolution=0.5"]), (WEDGING, ["rigid='hole'"]),
                            (str(SCENES / "hertz.toml"), [])):
        scene = load_scene(path, overrides)
        module = builder(scene)
        sizes = module.sizes(scene)
        gmsh_tools.start("estimate")
        module.generate(scene, sizes)
        actual = sum(len(tags) for tags in gmsh.model.mesh.getElements(2)[1])
        gmsh.model.remove()
        assert 0.5 < mesh_size.estimate(scene, sizes) / actual < 3.0, (path, overrides)
