"""Step a contact scene through its loads: increments, cuts, checkpoints.

An increment whose Newton iteration does not converge (`NewtonFailure`: too many
iterations, a residual that has stopped moving, a non-finite residual or a failed linear
solve) is retried from the last converged state, first with the contact stabilisation's
continuation, then by pseudo-transient continuation (a rigid body that must travel a few
contact elements to the contact that holds it), then halved, up to `SolverOptions.max_cuts`
times; after a success it grows back. The last cut gets one more try (`increment(load,
last_try=True)`). A run that still fails raises `SimulationFailed` naming the step, the time
and the residual history. Any other exception is a fault, not non-convergence: it ends the run
at once.
Each converged increment's output row goes to the `listeners`, called as listener(row, cuts)
(history file, progress).
"""
import functools
import json
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from femcontact.errors import InputError
from femcontact.io import write_json_atomic, write_npz_atomic


class SimulationFailed(RuntimeError):
    """The solver gave up on an increment after cutting it `max_cuts` times: `step` (its index)
    and `load` (the Load of the last increment tried) say where; `timings` (s) and `info` (the
    run's `newton_solves`), where the run that failed sets them, what it spent."""

    def __init__(self, message: str, step: int | None = None, load=None):
        super().__init__(message)
        self.step, self.load = step, load
        self.timings, self.info = {}, {}


def load_points(model) -> dict:
    """Named points of the rigid body in its shape frame (about its reference point)."""
    from femcontact.physics.signed_distance import reference_point

    Q0, origin = np.asarray(model.rigid["rotation"]), np.asarray(model.rigid["origin"])
    points = {name: Q0.T @ (np.asarray(x) - origin) - reference_point(model.rigid) for name, x in model.points.items()}
    points["reference"] = np.zeros(len(origin))
    return points


class Simulation:
    """A scene's problem, solver, schedule and the history of its increments.

    `options` are the scene's `SolverOptions`, shared with the Newton solver (`newton.options`).
    A time integrator (solver/dynamics.py) drives its increments through `prescribe`, `record`
    and `stabilized_solve`."""

    def __init__(self, scene: dict, comm=MPI.COMM_WORLD, listeners=()):
        from femcontact.config.solver import solver_options
        from femcontact.outputs.recorder import Recorder
        from femcontact.solver.linear import check_petsc_options
        from femcontact.problem.loading import Schedule
        from femcontact.solver.newton import SchurNewton
        from femcontact.problem.problem import Problem
        from geometry.model import build

        self.scene, self.timings, self.listeners = scene, {}, list(listeners)
        self.options = solver_options(scene)
        check_petsc_options(self.options.petsc_options)  # before meshing: a bad solver type is bad input
        start = time.perf_counter()
        self.model = build(scene, comm)
        self.timings["mesh"] = time.perf_counter() - start
        start = time.perf_counter()
        self.problem = Problem(scene, self.model)
        self.newton = SchurNewton(self.problem, self.options)
        self.recorder = Recorder(self.problem, self.newton)
        self.timings["forms"] = time.perf_counter() - start
        self.schedule = Schedule(scene, self.problem.rigid, load_points(self.model))
        self.history: list[dict] = []
        self.peak_load = self.peak_load_of(self.schedule.steps)
        self.stabilized_increments = 0
        self.stopped = ""  # why the run ended before its last step, if a stop condition did it
        self.events = []  # callables(index, row) -> str: a non-empty answer ends the run (`stopped`)
        self.last_change = None  # (step, dt, displacement change) of the last converged increment
        self.stabilization_force = 0.0
        self.pseudo_transient_exhausted = None  # the step in which pseudo-transient continuation gave up
        # step index: the rigid pose's change (mm, rad) when pseudo-transient continuation gave up there
        self.pseudo_travel = {}
        self.timings["solve"] = 0.0
        self.timings["output"] = 0.0

    def peak_load_of(self, steps: list) -> float:
        """The largest load of `steps` on the rigid body, force plus moment over its size, or of
        the effects (N): the scale of the stabilisation force a solve may keep."""
        size = self.problem.body_size
        return max([np.linalg.norm(step["force"] or [0.0]) + np.linalg.norm(step["moment"] or [0.0]) / size
                    for step in steps] + [self.problem.load_scale(), 1e-300])

    @property
    def dofs(self) -> int:
        return self.problem.dofs

    def run(self, first_step: int = 0) -> list[dict]:
        for index, step in enumerate(self.schedule.steps[first_step:], start=first_step):
            if not self.run_step(index, step):
                break
        return self.history

    # -- checkpoints: a study's shared prefix is computed once --------------------------------
    def save_checkpoint(self, directory: Path) -> None:
        """Write this rank's state after the steps run so far (restart needs the same ranks)."""
        comm = self.problem.mesh.comm
        directory = Path(directory)
        if comm.rank == 0:
            directory.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        write_npz_atomic(directory / f"rank{comm.rank}.npz", compressed=False, **self.problem.state())
        if comm.rank == 0:
            write_json_atomic(directory / "checkpoint.json", {"steps": len(self.schedule.steps), "ranks": comm.size,
                                                              "history": self.history})

    def load_checkpoint(self, directory: Path) -> int:
        """Restore a checkpoint; returns the number of steps it holds."""
        comm = self.problem.mesh.comm
        meta = json.loads((Path(directory) / "checkpoint.json").read_text())
        if meta["ranks"] != comm.size:
            raise InputError(f"--restart {directory}: written on {meta['ranks']} ranks, run on {comm.size}")
        self.problem.restore(dict(np.load(Path(directory) / f"rank{comm.rank}.npz")))
        for row in meta["history"]:
            self.record(row)
        return meta["steps"]

    def record(self, row: dict, cuts: int = 0) -> None:
        """Append an increment's output row to the history and pass it to the listeners."""
        self.history.append(row)
        for listener in self.listeners:
            listener(row, cuts)

    def run_step(self, index: int, step: dict) -> bool:
        """Advance through one step with adaptive increments; False when the step's stop
        condition (|row[stop.column]| > stop.value) or an event ended the run early (`self.stopped`)."""
        from femcontact.solver.newton import NewtonFailure

        nominal = step["duration"] / step["increments"]
        t, dt, cuts = 0.0, nominal, 0
        max_cuts = self.options.max_cuts
        while t < step["duration"] * (1 - 1e-12):
            dt = min(dt, step["duration"] - t)
            load = self.schedule.load(index, t + dt, dt)
            try:
                row = self.increment(load)
            except NewtonFailure as error:
                if cuts < max_cuts:
                    cuts += 1
                    dt /= 2
                    continue
                try:
                    row = self.increment(load, last_try=True)
                except NewtonFailure:
                    raise SimulationFailed(f"step {step['name']!r} at t = {load.time:.6g} s (dt = {dt:.3g} s) "
                                           f"after {cuts} cuts: {error}", index, load) from None
            self.record(row, cuts)
            stop = step["stop"]
            if stop["column"] and abs(row.get(stop["column"], 0.0)) > stop["value"]:
                self.stopped = f"step {step['name']!r}: |{stop['column']}| > {stop['value']:g} at t = {load.time:.6g} s"
                return False
            self.stopped = next((text for text in (event(index, row) for event in self.events) if text), "")
            if self.stopped:
                return False
            t += dt
            if cuts and row["newton_iterations"] <= self.options.max_iterations // 2:
                dt, cuts = min(2 * dt, nominal), cuts - 1
        return True

    def increment(self, load, last_try: bool = False) -> dict:
        """Solve one increment from the last converged state (restored on any failure): the
        plain Newton solve, then the stabilised and the pseudo-transient continuation (given up
        past `beyond_reach`; once it gave up, not again in the step); or (`last_try`, an
        increment that failed at every cut) pseudo-transient continuation from here, then every
        contact stuck first (`locked_first_solve`). Returns its output row, computed before the
        history moves on."""
        from femcontact.solver.newton import NewtonFailure

        p = self.problem
        state = p.state()
        p.begin_increment(load)
        start = time.perf_counter()
        try:
            self._predict(load)
            self.prescribe(load)
            self.stabilization_force = 0.0
            if last_try:
                ways = [functools.partial(self.pseudo_transient_solve, persist=True), self.locked_first_solve]
            else:
                ways = [self.plain_solve, self.stabilized_solve]
                if self.pseudo_transient_exhausted != load.step:
                    ways.append(functools.partial(self.pseudo_transient_solve, gone=self.beyond_reach))
            for k, way in enumerate(ways):
                try:
                    iterations = way(load)
                    break
                except NewtonFailure:
                    if k == len(ways) - 1:
                        raise
                    p.restore(state)
                    self.prescribe(load)
        except BaseException:
            p.restore(state)
            raise
        finally:
            self.timings["solve"] += time.perf_counter() - start
        start = time.perf_counter()
        row = self.recorder.row(load, iterations, self.stabilization_force)
        self.timings["output"] += time.perf_counter() - start
        p.commit(load.dt)
        self.last_change = (load.step, load.dt, p.u.x.array - state["u"])
        return row

    def beyond_reach(self, travel) -> bool:
        """Whether a pose change `travel` (mm, rad) carries the rigid body farther than
        `pseudo_reach` contact element sizes (`Problem.rigid_length`, as the trust region
        measures a step): where pseudo-transient continuation carries it that far in an increment that
        can still be cut, it slides along the load instead of settling near where the increment
        began, and the cut increment follows the load (measured in docs/stability.md, "The
        reach of pseudo-transient continuation")."""
        p = self.problem
        return bool(p.rigid_length(travel) > self.options.pseudo_reach * p.contact_size)

    def _predict(self, load) -> None:
        """Where no rigid dof is free (the rigid body's motion is all prescribed), start from the
        last converged displacement plus the last increment's change scaled to this dt (same step
        only): the deformable body follows the prescribed motion, also where the rigid body
        recedes and the contact would otherwise start open. Where a rigid dof is free (loads
        given as forces), start from the last converged state: the body's pose may change
        configuration between increments, and the extrapolated start costs more Newton
        iterations (docs/stability.md, "The first guess of an increment")."""
        if self.problem.rigid.free.any() or self.last_change is None:
            return
        step, dt, change = self.last_change
        if step == load.step and dt > 0:
            self.problem.u.x.array[:] += (load.dt / dt) * change

    def prescribe(self, load) -> None:
        """Set the rigid dofs that are not free to the load's prescribed motion (mm, rad)."""
        rigid = self.problem.rigid
        rigid.values[~rigid.free] = load.motion[~rigid.free]
        rigid.sync()

    def plain_solve(self, load) -> int:
        """Newton on the exact equations from the last converged state. Where several equilibria
        may hold the load (`Problem.path_dependent`: friction) and the rigid body floats there
        (`SchurNewton.solve`'s `stiff_start`), the stabilised continuation follows the load from
        that state instead: a free first step could carry the body to another equilibrium.
        Without friction one equilibrium holds the load, wherever Newton starts."""
        return self.newton.solve(load, stiff_start=self.problem.path_dependent())

    def stabilized_solve(self, load) -> int:
        """Continuation in the contact stabilisation down to zero. Where one equilibrium holds
        the load whatever the path (`Problem.path_dependent`: no friction), the exact equations
        (last factor) are tried at once from the first factor's solution, and the other factors
        are taken only if they fail; with friction every factor is taken in turn, which keeps the
        stick-slip state near the loading path. If the exact equations still fail, as for a body
        left in neutral equilibrium with vanishing contact forces, the solution of the smallest
        factor that converged is kept and its stabilisation force (N) is reported in the history."""
        from femcontact.solver.newton import NewtonFailure

        p, iterations = self.problem, 0
        first, *rest = self.options.stabilization_factors

        def spring_force() -> float:  # the spring's force on the rigid body (N)
            return float(np.linalg.norm(self.newton.stabilization_load()[: p.dim]))

        self.stabilized_increments += 1
        try:
            self.newton.stabilize(first)
            iterations += self.newton.solve(load)
            accepted, self.stabilization_force = p.state(), spring_force()
            if rest and not p.path_dependent():
                self.newton.stabilize(rest[-1])
                try:
                    iterations += self.newton.solve(load)
                    self.stabilization_force = spring_force()
                    return iterations
                except NewtonFailure:
                    p.restore(accepted)
            for factor in rest:
                self.newton.stabilize(factor)
                try:
                    iterations += self.newton.solve(load)
                except NewtonFailure:
                    if self.stabilization_force > self.options.stabilization_tolerance * self.peak_load:
                        raise
                    p.restore(accepted)
                    break
                accepted, self.stabilization_force = p.state(), spring_force()
        finally:
            self.newton.stabilize(0.0)
        return iterations

    def pseudo_transient_solve(self, load, persist: bool = False, gone=None) -> int:
        """Pseudo-transient continuation on the rigid body's pose (Kelley and Keyes): the
        stabilisation spring ties the body to a pose near its own at the start of each pseudo
        step, so a body without stiffness in some direction (pivoting on one contact node after
        the other contact opened) travels in bounded steps until it meets what holds it.

        - Each converged pseudo step commits the contact's history (`Problem.commit_contacts`):
          friction anchors follow the body along its way, so a contact that slid on the way sticks
          where the body comes to rest. The material's history (plastic strain) is not committed:
          the pseudo path is not the loading path, and with momentum it may press a contact
          harder than the load ever does.
        - Where the linear solves are direct, the tie runs ahead of the body by `pseudo_momentum`
          times its last pseudo step (heavy-ball momentum), so a body driven by a steady
          unbalanced load gathers speed; where the body falls behind its tie (it brakes) or a
          pseudo step fails, it starts again from rest. Momentum carries the linear solves'
          error along the path, and the committed anchors keep it: an iterative solver's (its
          solves stop at 1e-6 of the right-hand side) would make the rest state depend on the
          number of ranks, so it goes without.
        - A converged pseudo step softens the spring `pseudo_softening` times, down to the
          stiffness of the last failed one times `pseudo_softening`; a failed one is retried that
          much stiffer.
        - When a pseudo step barely loads the spring (`stabilization_tolerance` of the peak load)
          the body is at rest: the exact equations are solved from there (failing that, the state
          at rest is kept and its spring force reported, as in `stabilized_solve`).

        It gives up after `pseudo_failures` failed pseudo steps or `pseudo_iterations` Newton
        iterations (all `SolverOptions`), and then for the rest of the step except the last try
        of an increment (`increment(last_try=True)`, `persist`): there, where no cut is left to
        follow the load more closely, only failures in a row count (a failure followed by
        converged pseudo steps is progress). The body's travel when it gives up (its
        pose's change at the last converged pseudo step, mm and rad) is kept by step in
        `pseudo_travel`: how far the load carried it without finding rest. `gone(travel)`, if
        given, ends it (BodyGone, also for the rest of the step) as soon as it returns true for
        that change: the body has gone farther than any answer the caller wants (a probe's peg
        that let go, or `beyond_reach` where the increment can still be cut)."""
        from femcontact.solver.newton import BodyGone, NewtonFailure

        p, options, iterations, spent = self.problem, self.options, 0, 0
        failures, failed = 0, 0  # failed pseudo steps counted (in a row where `persist`), in all
        momentum = options.pseudo_momentum if self.newton.linear.direct else 0.0
        factor, floor, pose = 1.0, 0.0, p.rigid.values.copy()
        velocity = np.zeros_like(pose)  # the pose's change in the last pseudo step (mm, rad)
        travel = np.zeros_like(pose)  # the pose's change at the last converged pseudo step (mm, rad)
        try:
            while failures < options.pseudo_failures and spent < options.pseudo_iterations:
                start = p.state()
                tie = p.rigid.values + momentum * velocity
                self.newton.stabilize(factor, tie_pose=tie)
                try:
                    taken = self.newton.solve(load)
                except NewtonFailure as failure:
                    p.restore(start)
                    spent += len(failure.history)
                    failures, failed = failures + 1, failed + 1
                    factor *= options.pseudo_softening
                    floor, velocity = factor, np.zeros_like(pose)
                    continue
                iterations, spent = iterations + taken, spent + taken
                failures = 0 if persist else failures
                p.commit_contacts()
                force = self.newton.stabilization_force()
                if force <= options.stabilization_tolerance * self.peak_load:
                    rest = p.state()
                    self.newton.stabilize(0.0)
                    try:
                        iterations += self.newton.solve(load)
                        self.stabilization_force = 0.0
                    except NewtonFailure:
                        p.restore(rest)
                        self.stabilization_force = force
                    return iterations
                factor = max(factor / options.pseudo_softening, floor)
                moved = p.rigid.values - start["r"]
                braking = (p.rigid.values - tie) @ self.newton.stabilization @ moved <= 0
                velocity = np.zeros_like(pose) if braking else moved
                travel = p.rigid.values - pose
                if gone is not None and gone(travel):
                    self.pseudo_transient_exhausted = load.step
                    raise BodyGone(f"the rigid body went on by pseudo-transient continuation ({spent} Newton "
                                   f"iterations; it moved by {np.array2string(travel, precision=4)} (mm, rad))", [])
        finally:
            self.newton.stabilize(0.0)
        self.pseudo_transient_exhausted = load.step
        self.pseudo_travel[load.step] = travel
        raise NewtonFailure(f"the rigid body did not come to rest by pseudo-transient continuation "
                            f"({failed} failed pseudo steps, {spent} Newton iterations; it moved by "
                            f"{np.array2string(travel, precision=4)} (mm, rad))", [])

    def locked_first_solve(self, load) -> int:
        """The increment solved with every contact point stuck (`Problem.lock_contacts`), then with
        the scene's friction law from there. Where Newton cycles between stick and slip (a
        snap-fit apex pushed along a steep nose: no sliding equilibrium exists) the state in
        which nothing slips during the increment may be an equilibrium of the real law, and is
        then found from it."""
        from femcontact.solver.newton import NewtonFailure

        p = self.problem
        if not p.lock_contacts(True):
            raise NewtonFailure("no contact law to lock", [])
        try:
            iterations = self.newton.solve(load)
        finally:
            p.lock_contacts(False)
        return iterations + self.newton.solve(load)

    def newton_solves(self) -> dict:
        """Where the solve time went: for each way a Newton solve ended (`newton.SOLVE_KINDS`: plain,
        continuation, failed), its solves, Newton iterations and seconds. A slow run that spends
        most of it in failed solves gave up many tries before an increment converged; one that
        spends it in the continuation let the body travel far to rest."""
        return {kind: dict(counts) for kind, counts in self.newton.solves.items()}

    def step_end_rows(self) -> dict:
        """The last row of every step, by step name."""
        return {row["step"]: row for row in self.history}
