"""Run a contact scene: mesh, build the problem, step through the loads, report.

Increments that fail (Newton or linear solver) are halved and retried up to
`solver.max_cuts` times; after a success the increment grows back. A run that
still fails raises `SimulationFailed` naming the step, the time and the residual
history; nothing half-done is reported as a result.
"""
import csv
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from femcontact.errors import InputError


STABILIZATION_FACTORS = (1.0, 1e-2, 1e-4, 1e-6, 0.0)
"""Continuation of the contact stabilisation after a plain Newton failure: the last is exact."""
STABILIZATION_TOLERANCE = 1e-3
"""Largest stabilisation force kept, relative to the scene's peak load on the rigid body."""


class SimulationFailed(RuntimeError):
    """The solver gave up on an increment after cutting it `max_cuts` times."""


def load_points(model, rigid) -> dict:
    """Named points of the rigid body in its shape frame (about its reference point)."""
    from femcontact.obstacle import reference_point

    Q0, origin = np.asarray(model.rigid["rotation"]), np.asarray(model.rigid["origin"])
    points = {name: Q0.T @ (np.asarray(x) - origin) - reference_point(model.rigid) for name, x in model.points.items()}
    points["reference"] = np.zeros(len(origin))
    return points


class Simulation:
    """A scene's problem, solver, schedule and the history of its increments."""

    def __init__(self, scene: dict, comm=MPI.COMM_WORLD):
        from femcontact.loading import Schedule
        from femcontact.newton import SchurNewton
        from femcontact.outputs import Recorder
        from femcontact.problem import Problem
        from geometry.model import build

        self.scene, self.timings = scene, {}
        start = time.perf_counter()
        self.model = build(scene, comm)
        self.timings["mesh"] = time.perf_counter() - start
        start = time.perf_counter()
        self.problem = Problem(scene, self.model)
        self.newton = SchurNewton(self.problem)
        self.recorder = Recorder(self.problem, self.newton)
        self.timings["forms"] = time.perf_counter() - start
        weight = np.zeros(scene["dim"])
        if "gravity" in scene["effects"]:
            weight[-1] = -self.problem.rigid.mass * scene["dynamics"]["gravity"]
        self.schedule = Schedule(scene, self.problem.rigid, load_points(self.model, self.problem.rigid), weight)
        self.history: list[dict] = []
        size = self.problem.shape["scale"]
        self.peak_load = max([np.linalg.norm(step["force"] or [0.0]) + np.linalg.norm(step["moment"] or [0.0]) / size
                              for step in scene["steps"]] + [np.linalg.norm(weight), 1e-300])
        self.stabilized_increments = 0
        self.stabilization_force = 0.0
        self.timings["solve"] = 0.0
        self.timings["output"] = 0.0

    @property
    def dofs(self) -> int:
        V = self.problem.V
        return V.dofmap.index_map.size_global * V.dofmap.index_map_bs

    def run(self, first_step: int = 0) -> list[dict]:
        for index, step in enumerate(self.scene["steps"][first_step:], start=first_step):
            self.run_step(index, step)
        return self.history

    # -- checkpoints: a study's shared prefix is computed once --------------------------------
    def save_checkpoint(self, directory: Path) -> None:
        """Write this rank's state after the steps run so far (restart needs the same ranks)."""
        p, comm = self.problem, self.problem.mesh.comm
        directory = Path(directory)
        if comm.rank == 0:
            directory.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        corners = p.corners
        np.savez(directory / f"rank{comm.rank}.npz", r_old=p.rigid.r_old.value, tangential_old=corners.tangential_old,
                 corner_old=corners.corner_old, corner_u_old=corners.u_old, **p.state())
        if comm.rank == 0:
            from femcontact.run import write_json_atomic

            write_json_atomic(directory / "checkpoint.json", {"steps": len(self.scene["steps"]), "ranks": comm.size,
                                                              "history": self.history})

    def load_checkpoint(self, directory: Path) -> int:
        """Restore a checkpoint; returns the number of steps it holds."""
        import json

        p, comm = self.problem, self.problem.mesh.comm
        meta = json.loads((Path(directory) / "checkpoint.json").read_text())
        if meta["ranks"] != comm.size:
            raise InputError(f"--restart {directory}: written on {meta['ranks']} ranks, run on {comm.size}")
        data = dict(np.load(Path(directory) / f"rank{comm.rank}.npz"))
        p.restore(data)
        p.rigid.r_old.value[:] = data["r_old"]
        p.corners.tangential_old[:] = data["tangential_old"]
        p.corners.corner_old, p.corners.u_old = data["corner_old"], data["corner_u_old"]
        self.history = meta["history"]
        return meta["steps"]

    def run_step(self, index: int, step: dict) -> None:
        """Advance through one step with adaptive increments."""
        nominal = step["duration"] / step["increments"]
        t, dt, cuts = 0.0, nominal, 0
        max_cuts = self.scene["solver"]["max_cuts"]
        while t < step["duration"] * (1 - 1e-12):
            dt = min(dt, step["duration"] - t)
            load = self.schedule.load(index, t + dt, dt)
            try:
                self.history.append(self.increment(load))
            except (RuntimeError, FloatingPointError) as error:
                if cuts >= max_cuts:
                    raise SimulationFailed(f"step {step['name']!r} at t = {load.time:.6g} s (dt = {dt:.3g} s) "
                                           f"after {cuts} cuts: {error}") from None
                cuts += 1
                dt /= 2
                continue
            t += dt
            if cuts and self.history[-1]["newton_iterations"] <= self.scene["solver"]["max_iterations"] // 2:
                dt, cuts = min(2 * dt, nominal), cuts - 1

    def increment(self, load) -> dict:
        """Solve one increment from the last converged state (restored on failure);
        returns its output row, computed before the history moves on."""
        from femcontact.newton import NewtonFailure

        p = self.problem
        state = p.state()
        free = p.rigid.free
        p.rigid.values[~free] = load.motion[~free]
        p.rigid.sync()
        p.set_time_step(load.dt)
        start = time.perf_counter()
        try:
            self.stabilization_force = 0.0
            try:
                iterations = self.newton.solve(load)
            except NewtonFailure:
                p.restore(state)
                p.rigid.values[~free] = load.motion[~free]
                p.rigid.sync()
                iterations = self.stabilized_solve(load)
        except NewtonFailure:
            p.restore(state)
            raise
        finally:
            self.timings["solve"] += time.perf_counter() - start
        start = time.perf_counter()
        row = {**self.recorder.row(load, iterations), "stabilization_force": self.stabilization_force}
        self.timings["output"] += time.perf_counter() - start
        if "anchor" in p.history:
            self.newton.update_anchors()
        p.commit(load.dt)
        return row

    def stabilized_solve(self, load) -> int:
        """Continuation in the contact stabilisation down to zero. If the exact equations
        (last factor) still fail, as for a body left in neutral equilibrium with vanishing
        contact forces, the solution of the smallest factor that converged is kept and its
        stabilisation force (N) is reported in the history."""
        from femcontact.newton import NewtonFailure

        p, iterations, accepted = self.problem, 0, None
        self.stabilized_increments += 1
        try:
            for factor in STABILIZATION_FACTORS:
                self.newton.stabilize(factor)
                try:
                    iterations += self.newton.solve(load)
                except NewtonFailure:
                    if accepted is None or self.stabilization_force > STABILIZATION_TOLERANCE * self.peak_load:
                        raise
                    p.restore(accepted)
                    break
                accepted = p.state()
                force = self.newton.stabilization @ (p.rigid.values - p.rigid.r_old.value)
                self.stabilization_force = float(np.linalg.norm(force[: p.dim]))
        finally:
            self.newton.stabilize(0.0)
        return iterations

    def write_history(self, path: Path) -> None:
        if self.problem.mesh.comm.rank != 0 or not self.history:
            return
        keys = list(self.history[0])
        with open(path, "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=keys, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(self.history)

    def step_end_rows(self) -> dict:
        """The last row of every step, by step name."""
        return {row["step"]: row for row in self.history}


def summary_metrics(simulation: Simulation) -> dict:
    """Flat metrics: every step-end output as '<step>.<quantity>', plus totals."""
    metrics = {}
    for step, row in simulation.step_end_rows().items():
        for key, value in row.items():
            if key != "step":
                metrics[f"{step}.{key}"] = value
    metrics["newton_iterations"] = sum(row["newton_iterations"] for row in simulation.history)
    metrics["increments"] = len(simulation.history)
    metrics["max_von_mises"] = max(row["max_von_mises"] for row in simulation.history)
    metrics["yielded"] = any(row["yielded"] for row in simulation.history)
    return metrics


def run_scene(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None) -> dict:
    """Run a resolved contact scene; write history.csv and fields.npz into case_dir.
    `checkpoint`: also save the final state in case_dir/checkpoint; `restart`: start from
    such a checkpoint (same first steps, same ranks) and run only the later steps."""
    from femcontact.fields import write_fields

    if not scene["steps"]:
        raise InputError("steps: a contact scene needs at least one step")
    simulation = Simulation(scene)
    simulation.run(simulation.load_checkpoint(restart) if restart else 0)
    case_dir = Path(case_dir)
    if checkpoint:
        simulation.save_checkpoint(case_dir / "checkpoint")
    start = time.perf_counter()
    simulation.write_history(case_dir / "history.csv")
    write_fields(simulation, case_dir)
    simulation.timings["output"] += time.perf_counter() - start
    metrics = summary_metrics(simulation)
    if scene["geometry"] == "peg_in_hole":
        from femcontact.wedging import wedge_metrics

        metrics.update(wedge_metrics(simulation))
    info = {"dofs": simulation.dofs, "newton_iterations": metrics["newton_iterations"],
            "effects": list(scene["effects"]), "built": simulation.problem.built,
            "stabilized_increments": simulation.stabilized_increments}
    return {"metrics": metrics, "timings": simulation.timings, "info": info}
