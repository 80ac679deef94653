"""A single run as a user sees it: progress while it works, history streamed so a killed run
keeps what it computed, and faults that end the run instead of being retried as cuts."""
import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from femcontact.families import load_scene

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "wedging_2d.toml"


def test_killed_run_keeps_the_increments_it_finished(tmp_path):
    out = tmp_path / "case"
    command = [sys.executable, "-m", "femcontact", "run", str(SCENE), "--set", "mesh.resolution=0.5",
               "--set", "steps.0.increments=40", "--out", str(out)]
    process = subprocess.Popen(command, cwd=ROOT, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    history = out / "history.csv"
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and process.poll() is None:
        if history.exists() and len(history.read_text().splitlines()) >= 3:  # header + 2 increments
            break
        time.sleep(0.01)
    process.send_signal(signal.SIGKILL)
    stderr = process.communicate()[1]
    rows = list(csv.DictReader(open(history)))
    assert len(rows) >= 2
    assert all(None not in row.values() and row["step"] == "load" for row in rows)  # whole rows only
    assert float(rows[1]["time"]) > float(rows[0]["time"]) > 0
    assert not (out / "result.json").exists()
    progress = [line for line in stderr.splitlines() if "step 1/2 'load'" in line]
    assert len(progress) >= 2 and "newton" in progress[0]


def test_a_fault_ends_the_run_at_once_with_the_state_restored(monkeypatch):
    """Only non-convergence is answered by cutting the increment; any other error is a fault."""
    from femcontact.solver import newton
    from femcontact.solver.stepping import Simulation

    simulation = Simulation(load_scene(SCENE, ["mesh.resolution=0.5"]))
    calls = []

    def broken(self, load, stiff_start=False):
        calls.append(load.time)
        self.problem.u.x.array[:] = np.nan  # a half-iterated state
        raise ValueError("a bug")

    monkeypatch.setattr(newton.SchurNewton, "solve", broken)
    with pytest.raises(ValueError, match="a bug"):
        simulation.run()
    assert len(calls) == 1  # not retried as a cut
    assert np.isfinite(simulation.problem.u.x.array).all()  # restored
    assert simulation.history == []


def test_python_m_femcontact_works_like_the_command():
    result = subprocess.run([sys.executable, "-m", "femcontact", "--help"], capture_output=True, text=True,
                            env={**os.environ}, cwd=ROOT)
    assert result.returncode == 0 and "run" in result.stdout and "study" in result.stdout


@pytest.mark.parametrize("preset, expected", [({}, "1"), ({"OMPI_MCA_ess_singleton_isolated": "0"}, "0")])
def test_a_process_without_a_launcher_starts_mpi_alone(preset, expected):
    """`femcontact run` and `hertz` outside mpirun: Open MPI's singleton without its helper daemon
    or transport probing (femcontact.process.SINGLETON_MPI), a user's own setting kept; MPI works."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}
    code = ("import os; from femcontact.process import start_mpi_for_meshing; MPI = start_mpi_for_meshing(); "
            "print(os.environ['OMPI_MCA_ess_singleton_isolated'], os.environ['OMPI_MCA_pml'], "
            "MPI.COMM_WORLD.allreduce(1), 'gmsh' in __import__('sys').modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={**env, **preset},
                            cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == [expected, "ob1", "1", "True"]


def test_the_command_ends_without_teardown_but_with_its_output_and_status():
    """femcontact.process.end_process: Python's and C's buffered output written, PETSc and MPI
    finalised (PETSc's -log_view prints at finalisation), the exit status kept."""
    code = ("import sys; from femcontact.process import end_process, start_mpi_for_meshing; MPI = start_mpi_for_meshing(); "
            "import petsc4py; petsc4py.init(['x', '-log_view']); from petsc4py import PETSc; "
            "print('written', end=''); sys.stderr.write('error'); end_process(3)")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT)
    assert result.returncode == 3
    assert result.stdout.startswith("written") and "PETSc Performance Summary" in result.stdout
    assert result.stderr.startswith("error")


def test_versions_are_read_without_pkg_resources_until_more_is_asked():
    """femcontact.process.VersionsOnly: UFL's and FFCx's version strings as importlib.metadata
    reads them, without importing pkg_resources; anything else loads the real module, once."""
    code = ("import sys, importlib.metadata as m; from femcontact.process import start_mpi_for_meshing; "
            "start_mpi_for_meshing(); import ufl, ffcx; stand_in = sys.modules['pkg_resources']; "
            "print(ufl.__version__ == m.version('fenics-ufl'), ffcx.__version__ == m.version('fenics-ffcx'), "
            "type(stand_in).__name__); working_set = stand_in.working_set; real = sys.modules['pkg_resources']; "
            "print(type(real).__name__, real is not stand_in, stand_in.working_set is working_set, "
            "sys.modules['pkg_resources'] is real)")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["True", "True", "VersionsOnly", "module", "True", "True", "True"]


def test_a_stop_column_ends_the_run_and_the_columns_are_the_history_header(tmp_path):
    """The columns a stop may name (checked before solving) are exactly history.csv's header,
    and a stop on one of them ends the run at the first increment past its value."""
    out = tmp_path / "case"
    scene = ROOT / "scenes" / "insertion_2d.toml"
    overrides = ["mesh.resolution=0.5", "steps.0.increments=10", "steps.0.stop.value=0.05"]
    code = subprocess.run([sys.executable, "-m", "femcontact", "run", str(scene), *sum((["--set", o] for o in overrides), []),
                           "--out", str(out), "--quiet"], cwd=ROOT).returncode
    assert code == 0
    with open(out / "history.csv") as file:
        rows = list(csv.DictReader(file))
    from femcontact.solver.stepping import Simulation

    columns = Simulation(load_scene(scene, overrides)).recorder.columns
    assert list(rows[0]) == columns
    assert 0 < len(rows) < 10 and abs(float(rows[-1]["support_Fy"])) > 0.05
    assert all(abs(float(row["support_Fy"])) <= 0.05 for row in rows[:-1])


def test_a_rows_newton_iterations_sum_the_solves_of_the_stabilisation_continuation(monkeypatch):
    """An increment whose plain solve fails is solved again at each stabilisation level; its row
    counts the iterations of every solve that led to it (solver.max_iterations bounds each solve,
    not the row, as its doc says)."""
    from femcontact.config.scene import SOLVER
    from femcontact.solver import newton
    from femcontact.solver.stepping import Simulation

    scene = load_scene(SCENE, ["mesh.resolution=0.5", "steps.0.increments=1"])
    simulation = Simulation(scene)
    real, solves = newton.SchurNewton.solve, []

    def first_fails(self, load, stiff_start=False):
        if not solves:
            solves.append(None)
            raise newton.NewtonFailure("no convergence in 40 iterations", [1.0])
        solves.append(real(self, load, stiff_start))
        return solves[-1]

    monkeypatch.setattr(newton.SchurNewton, "solve", first_fails)
    simulation.run_step(0, scene["steps"][0])
    counted = solves[1:]  # the failed plain solve is not counted
    assert len(counted) == len(simulation.options.stabilization_factors) and simulation.stabilized_increments == 1
    assert simulation.history[0]["newton_iterations"] == sum(counted) > max(counted)
    assert "sum over the solves that led to the converged increment" in SOLVER["max_iterations"].doc
