"""Beyond the thesis' dislodging (issue 14): degree of wedging, other ways out, pulse
optimisation and the 3-D pull-out, with the machinery of `scenarios.dislodging` (the wedged
state computed once, implicit-Euler pulls that stop at the located event "dislodged",
thresholds by bisection).

- Degree of wedging of a wedged state: its quasi-static pull-out force P over mu times the
  sum of the residual normal forces, P / (mu (N_A + N_B)): 1 when the pull has to overcome the
  full friction of both contacts (a peg that only translates), less when the peg can pivot
  out of the wedge.
- Ways out (2-D, loads at the peg top, `method_loads`): 'continuous' and 'pulse' (vertical
  pull), 'shake' (lateral pulses), 'twist' (moment pulses about the out-of-plane axis,
  magnitude F = M / d: the couple of two forces F on the peg's top corners d apart),
  'pull_shake' (a constant pull of `base_pull` x the pull-out plus lateral pulses). Shake and
  twist act against the wedging moment (the other sense wedges the peg harder). Reported:
  the peak force |F| (N; twist M / d) and the impulse |integral of F dt| (N*s; twist the
  angular impulse / d) from the start of the pull to the event.
- Pulse optimisation: frequency, duty, shape and peak force minimising the impulse to
  dislodge: a grid over frequency x duty per shape, then bounded Nelder-Mead (scipy) from the
  best grid point of each shape; the optimum re-run by a fresh simulation from the checkpoint.
- 3-D: quasi-static pull-out of the wedged cylinder along its axis and the torque about the
  axis at which it turns, by bisection, both in the one process that wedged it (a checkpoint
  written on 2 ranks did not restore: the 3-D mesh was partitioned differently in the next
  process); its 2-D estimates from the 3-D contact forces.
"""
import copy
import csv
import math
import time
from pathlib import Path

import numpy as np

from femcontact.scenarios.dislodging import (OBSERVE_STEP, PULL_STEP, Puller, one_dof_thresholds,
                                            wedged_simulation)
from femcontact.solver.loading import Schedule

SHAPES = ("triangle", "square", "haversine")
RETRIES = 2
"""A pull whose Newton iteration fails (seen while locating the opening of a twisted peg: the rigid
step swung back and forth) is run again from the wedged state with dt_max and the rise cap / 4."""


# -- loads ---------------------------------------------------------------------------------------

def unwedging_sign(scene: dict) -> float:
    """Sense (+1 counter-clockwise) of the moment that turns the peg back out of its wedge:
    against the wedging moment of the first step."""
    moment = (scene["steps"][0]["moment"] or [0.0])[0]
    return -1.0 if moment >= 0 else 1.0


def method_loads(method: str, magnitude: float, sign: float, width: float, base: float) -> dict:
    """Pull-step loads of a method of peak `magnitude` (N): `force` [Fx, Fy] (N) and `moment`
    [Mz] (N*mm) multiplied by the amplitude, `base` [Fx, Fy] (N) held constant through the pull
    and observe steps. A lateral force F_x at the top (above the reference point) turns the peg
    by -arm F_x, so shaking against the wedging moment pushes towards -sign."""
    loads = {"force": [0.0, 0.0], "moment": [0.0], "base": [0.0, 0.0]}
    if method in ("continuous", "pulse"):
        loads["force"] = [0.0, magnitude]
    elif method == "shake":
        loads["force"] = [-sign * magnitude, 0.0]
    elif method == "twist":
        loads["moment"] = [sign * magnitude * width]
    elif method == "pull_shake":
        loads.update(force=[-sign * magnitude, 0.0], base=[0.0, base])
    else:
        raise ValueError(f"unknown method {method!r}")
    return loads


class BaseSchedule(Schedule):
    """The scene's schedule plus a constant force (N) in the given steps."""

    def __init__(self, scene, rigid, points, base: dict):
        super().__init__(scene, rigid, points)
        self.base = base  # step index -> force (N)

    def load(self, index, t, dt):
        load = super().load(index, t, dt)
        if index in self.base:
            load.force = load.force + self.base[index]
        return load


def apply_method(sim, loads: dict, method: str, frequency: float, duty: float, shape: str) -> dict:
    """Set the pull and observe steps of `sim` (a DynamicSimulation) to `loads` (method_loads)
    at the peg top: a step force for 'continuous', else a pulse train; returns loads."""
    pull, observe = sim.scene["steps"][PULL_STEP], sim.scene["steps"][OBSERVE_STEP]
    pull.update(force=list(loads["force"]), moment=list(loads["moment"]), load_point="peg_top",
                amplitude="step" if method == "continuous" else "pulse",
                pulse={"frequency": float(frequency), "duty": float(duty), "shape": shape})
    observe.update(force=[], moment=[], amplitude="step", load_point="peg_top")
    constant = np.asarray(loads["base"], float)
    sim.schedule = BaseSchedule(sim.scene, sim.problem.rigid, sim.schedule.points,
                                {PULL_STEP: constant, OBSERVE_STEP: constant} if constant.any() else {})
    return loads


def load_impulse(schedule, elapsed: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact force (N*s) and moment (N*mm*s) impulses of the pull and observe steps over the
    first `elapsed` s of the pull, the constant base included."""
    from femcontact.scenarios.dynamics import step_impulse

    force, moment, t = 0.0, 0.0, elapsed
    for index in (PULL_STEP, OBSERVE_STEP):
        span = min(t, schedule.steps[index]["duration"])
        if span > 0:
            f, m = step_impulse(schedule, index, 0.0, span)
            force, moment = force + f + getattr(schedule, "base", {}).get(index, 0.0) * span, moment + m
        t -= span
    return np.asarray(force, float), np.asarray(moment, float)


def peak_and_impulse(method: str, loads: dict, force_impulse, moment_impulse, width: float) -> tuple[float, float]:
    """Peak force (N) and impulse (N*s) of a method in common units (twist: M / d)."""
    if method == "twist":
        return abs(loads["moment"][0]) / width, float(abs(moment_impulse[0])) / width
    peak = float(np.linalg.norm(np.add(loads["force"], loads["base"])))
    return peak, float(np.linalg.norm(force_impulse))


# -- pulls in 2-D ----------------------------------------------------------------------------------

class BeyondPuller(Puller):
    """The wedged 2-D peg and its pulls by any method, each restarting from the wedged state."""

    def __init__(self, scene: dict, restart=None, checkpoint=None):
        super().__init__(scene, restart, checkpoint)
        self.sign = unwedging_sign(scene)
        self.width = scene["peg"]["width"]

    def set_loads(self, method: str, magnitude: float, frequency: float = 50.0, duty: float = 1.0,
                  shape: str = "triangle") -> dict:
        base = self.settings["base_pull"] * self.pullout["quasi_static_pullout_N"]
        return apply_method(self.simulation, method_loads(method, magnitude, self.sign, self.width, base),
                            method, frequency, duty, shape)

    def run(self, method: str, magnitude: float, frequency: float = 50.0, duty: float = 1.0,
            shape: str = "triangle") -> dict:
        """One dynamic pull from the wedged state; its row."""
        from femcontact.scenarios.dynamics import Event

        from femcontact.solver.newton import NewtonFailure

        s, sim = self.settings, self.simulation
        start = time.perf_counter()
        for retry in range(RETRIES + 1):  # a Newton failure while locating the event: again with finer steps
            sim.resume(self.wedged)
            loads = self.set_loads(method, magnitude, frequency, duty, shape)
            try:
                outcome = sim.integrate([PULL_STEP, OBSERVE_STEP], Event(rise=s["rise"]), s["dt_max"] / 4 ** retry,
                                        s["dt_min"], s["max_rise_per_increment"] / 4 ** retry,
                                        settle_period=1 / frequency if method != "continuous" else 0.01)
                break
            except (NewtonFailure, RuntimeError, FloatingPointError):
                if retry == RETRIES:
                    raise
        row = {"case": s["case"], "method": method, "magnitude_N": float(magnitude),
               "pulse_hz": frequency if method != "continuous" else "", "duty": duty if method != "continuous" else "",
               "shape": shape if method != "continuous" else "", "dislodged": outcome.event is not None,
               "event": outcome.event or "", "dislodge_time_s": "", "increments": outcome.increments,
               "newton_iterations": outcome.newton_iterations, "settled": outcome.settled, "retries": retry,
               "wall_s": time.perf_counter() - start}
        duration = sim.scene["steps"][PULL_STEP]["duration"]
        elapsed = outcome.time - float(sim.schedule.start_times[PULL_STEP]) if outcome.event else duration
        peak, impulse = peak_and_impulse(method, loads, *load_impulse(sim.schedule, elapsed), self.width)
        row.update(peak_force_N=peak, impulse_Ns=impulse if outcome.event else "",
                   applied_impulse_Ns=impulse)  # to the event, or over the whole pull step if it holds
        if outcome.event:
            row["dislodge_time_s"] = elapsed
        return row

    def threshold(self, method: str, rows: list, frequency=50.0, duty=1.0, shape="triangle") -> dict:
        """Smallest peak magnitude (N) that dislodges, by bisection to `tolerance` from a bracket
        widened by factors of 2 (every pull appended to rows)."""
        tolerance = self.settings["tolerance"]
        pullout = self.pullout["quasi_static_pullout_N"]
        cache = {}

        def dislodges(magnitude):
            key = round(magnitude, 6)
            if key not in cache:
                cache[key] = self.run(method, key, frequency, duty, shape)
                rows.append(cache[key])
            return cache[key]["dislodged"]

        low, high = (pullout, 1.05 * pullout) if method in ("continuous", "pulse") else (0.5 * pullout, pullout)
        for _ in range(12):
            if not dislodges(high):
                low, high = high, 2 * high
            elif dislodges(low):
                low, high = low / 2, low
            else:
                break
        else:
            raise RuntimeError(f"method {method}: no bracket of the threshold between {low:.4g} and {high:.4g} N")
        while high - low > tolerance * (1 + 1e-9):
            middle = (low + high) / 2
            if dislodges(middle):
                high = middle
            else:
                low = middle
        at = cache[round(high, 6)]
        return {"threshold_force_N": at["peak_force_N"], "threshold_magnitude_N": high, "bracket_N": high - low,
                "impulse_at_threshold_Ns": at["impulse_Ns"], "dislodge_time_at_threshold_s": at["dislodge_time_s"]}


# -- pulse optimisation ------------------------------------------------------------------------------

def objective(row: dict) -> float:
    """Impulse to dislodge (N*s); a pull that holds scores twice the impulse it applied over
    the whole pull step (worse than any pull that dislodges with it)."""
    return float(row["impulse_Ns"]) if row["dislodged"] else 2.0 * float(row["applied_impulse_Ns"])


def optimise(puller: BeyondPuller, rows: list) -> dict:
    """Pulse (vertical pull) minimising the impulse to dislodge over frequency, duty, shape and
    peak force: a grid over frequency x duty at `grid_magnitude` x pull-out for each shape, then
    bounded Nelder-Mead over (log10 Hz, duty, log peak) from each shape's best grid point
    (`evaluations` pulls per shape). Every pull is appended to rows (column `phase`)."""
    from scipy.optimize import minimize

    s = puller.settings
    pullout = puller.pullout["quasi_static_pullout_N"]
    cache = {}

    def evaluate(shape, hz, duty, magnitude, phase):
        key = (shape, round(hz, 6), round(duty, 6), round(magnitude, 6))
        if key not in cache:
            row = puller.run("pulse", key[3], key[1], key[2], shape)
            row.update(phase=phase, objective_Ns=objective(row))
            rows.append(row)
            cache[key] = row
        return cache[key]["objective_Ns"]

    for shape in SHAPES:
        for hz in s["grid_hz"]:
            for duty in s["grid_duty"]:
                evaluate(shape, hz, duty, s["grid_magnitude"] * pullout, "grid")
    bounds = [tuple(np.log10(s["frequency_range"])), tuple(s["duty_range"]), tuple(np.log(s["magnitude_range"]))]
    best = None
    for shape in SHAPES:
        grid = [(k, row) for k, row in cache.items() if k[0] == shape]
        (_, hz, duty, magnitude), _ = min(grid, key=lambda item: item[1]["objective_Ns"])
        x0 = np.clip([math.log10(hz), duty, math.log(magnitude / pullout)], *np.array(bounds).T)
        simplex = np.array([x0] + [x0 + step for step in np.diag([-0.3, -0.15, 0.4])])
        simplex = np.clip(simplex, *np.array(bounds).T)

        def fun(x, shape=shape):
            return evaluate(shape, 10 ** x[0], x[1], math.exp(x[2]) * pullout, "nelder-mead")

        result = minimize(fun, x0, method="Nelder-Mead", bounds=bounds,
                          options={"maxfev": s["evaluations"], "initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-6})
        candidates = [(k, row) for k, row in cache.items() if k[0] == shape]
        key, row = min(candidates, key=lambda item: item[1]["objective_Ns"])
        if best is None or row["objective_Ns"] < best[1]["objective_Ns"]:
            best = (key, row, int(result.nfev))
    (shape, hz, duty, magnitude), row, _ = best
    return {"shape": shape, "pulse_hz": hz, "duty": duty, "peak_force_N": magnitude,
            "peak_over_pullout": magnitude / pullout, "objective_impulse_Ns": row["objective_Ns"],
            "dislodge_time_s": row["dislodge_time_s"], "evaluations": len(cache), "quasi_static_pullout_N": pullout}


def verify(scene: dict, restart, optimum: dict) -> dict:
    """The optimum re-run by a fresh simulation (new solver, state read from the checkpoint
    `restart`, or wedged again without one): its impulse and the relative difference."""
    fresh = BeyondPuller(copy.deepcopy(scene), restart)
    row = fresh.run("pulse", optimum["peak_force_N"], optimum["pulse_hz"], optimum["duty"], optimum["shape"])
    impulse = objective(row)
    return {"verified_impulse_Ns": impulse, "verified_dislodged": bool(row["dislodged"]),
            "verified_relative_difference": abs(impulse - optimum["objective_impulse_Ns"]) / optimum["objective_impulse_Ns"]}


# -- 3-D quasi-static pull-out -----------------------------------------------------------------------

def contacts_on_axis(row: dict, axis: np.ndarray, dim: int) -> dict:
    """Normal and tangential (along the peg axis, positive out of the hole) forces on the peg
    (N) at A (block mouth on the -x side, normal perpendicular to the peg's side in the plane of
    the tilt) and B (the tip on the +x wall, normal -x). Vertical = y in 2-D, z in 3-D."""
    v = dim - 1
    a = np.array([axis[0], axis[v]])
    n_A = np.array([a[1], -a[0]])
    on_A = -np.array([row["contact_A_Fx"], row[f"contact_A_F{'xyz'[v]}"]])
    on_B = -np.array([row["contact_B_Fx"], row[f"contact_B_F{'xyz'[v]}"]])
    return {"N_A": float(on_A @ n_A), "T_A": float(on_A @ a), "N_B": float(-on_B[0]), "T_B": float(on_B[1])}


class Wedge3D:
    """The wedged 3-D peg (quasi-static, no inertia) and its pull-out along its axis."""

    def __init__(self, scene: dict, restart=None, checkpoint=None):
        self.scene, self.settings = scene, scene["dislodging"]
        self.simulation, self.wedge_time = wedged_simulation(scene, restart, checkpoint)
        sim = self.simulation
        rigid = sim.problem.rigid
        self.wedged_row, self.wedged = sim.history[-1], sim.snapshot()
        self.axis = rigid_axis(rigid)
        self.tilt = rigid.tilt()
        self.contacts = contacts_on_axis(self.wedged_row, self.axis, 3)

    def holds(self, magnitude: float, method: str) -> bool:
        """Does the wedge hold a force (N) along the peg axis ('continuous') or a torque (N*mm)
        about it ('twist') quasi-statically? Yes when the exact Newton iteration converges from
        the wedged state with both contact zones loaded and the peg moved by less than `lift`
        (mm; a rotation times the peg radius)."""
        from femcontact.solver.newton import NewtonFailure

        sim, s = self.simulation, self.settings
        sim.resume(self.wedged)
        pull = sim.scene["steps"][PULL_STEP]
        vector = list(magnitude * self.axis)
        pull.update(force=vector if method == "continuous" else [], moment=vector if method == "twist" else [],
                    amplitude="step", load_point="peg_top")
        sim.schedule = Schedule(sim.scene, sim.problem.rigid, sim.schedule.points)
        duration = pull["duration"]
        load = sim.schedule.load(PULL_STEP, duration, duration)
        r0 = self.wedged["state"]["r"]
        load.motion = r0.copy()
        try:
            sim.solve(load, stabilize=False)
        except (NewtonFailure, FloatingPointError, RuntimeError):
            return False
        r = sim.problem.rigid.values
        moved = (float(np.dot(r[:3] - r0[:3], self.axis)) if method == "continuous"
                 else float(np.dot(r[3:] - r0[3:], self.axis)) * self.scene["peg"]["width"] / 2)
        return bool(np.all(sim.zone_forces() > 0) and abs(moved) < s["lift"])

    def threshold(self, method: str, high: float) -> dict:
        """Largest magnitude the wedge holds, by bisection from [0, high] (high doubled until the
        wedge lets go, at most 4 times)."""
        tolerance = self.settings["tolerance"] * (self.scene["peg"]["width"] / 2 if method == "twist" else 1.0)
        low, solves = 0.0, 1
        while self.holds(high, method):
            low, high, solves = high, 2 * high, solves + 1
            if solves > 5:
                raise RuntimeError(f"the 3-D wedge holds {low:.4g} ({method})")
        while high - low > tolerance * (1 + 1e-9):
            middle = (low + high) / 2
            solves += 1
            if self.holds(middle, method):
                low = middle
            else:
                high = middle
        return {"threshold": low, "bracket": high - low, "solves": solves}


def rigid_axis(rigid) -> np.ndarray:
    """The peg axis (unit, global) at the current pose."""
    from femcontact.physics.rotation import rotation_numpy

    return rotation_numpy(rigid.split(rigid.values)[1]) @ rigid.Q0[:, -1]


def run_3d(scene: dict, case_dir: Path, checkpoint: bool, restart) -> dict:
    s = scene["dislodging"]
    mu = scene["contact"]["mu"]
    start = time.perf_counter()
    wedge = Wedge3D(scene, restart, Path(case_dir) / "checkpoint" if checkpoint else None)
    c = wedge.contacts
    metrics = {**{f"wedged_{k}": v for k, v in c.items()}, "tilt_deg": math.degrees(wedge.tilt),
               "sum_normal_N": c["N_A"] + c["N_B"], "wedge_time_s": wedge.wedge_time,
               **{f"one_dof_{k}_N": v for k, v in one_dof_thresholds(**c, tilt=wedge.tilt, mu=mu).items()}}
    info = {"dofs": wedge.simulation.dofs, "effects": list(scene["effects"])}
    if len(scene["steps"]) <= PULL_STEP:
        return {"metrics": metrics, "timings": {"wedge": wedge.wedge_time}, "info": info}
    friction, radius = mu * metrics["sum_normal_N"], scene["peg"]["width"] / 2
    start_pull = time.perf_counter()
    pull = wedge.threshold("continuous", 2 * metrics["one_dof_first_slip_N"])  # the 2-D pull-out: ~first slip
    metrics.update(threshold_force_N=pull["threshold"], bracket_N=pull["bracket"], pull_solves=pull["solves"],
                   degree_of_wedging=pull["threshold"] / friction, pull_time_s=time.perf_counter() - start_pull)
    start_twist = time.perf_counter()
    twist = wedge.threshold("twist", friction * radius)
    metrics.update(twist_threshold_moment_Nmm=twist["threshold"], twist_bracket_Nmm=twist["bracket"],
                   twist_solves=twist["solves"], twist_over_friction_torque=twist["threshold"] / (friction * radius),
                   twist_time_s=time.perf_counter() - start_twist)
    return {"metrics": metrics, "timings": {"wedge": wedge.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}


# -- one study case ----------------------------------------------------------------------------------

PULL_COLUMNS = ["case", "method", "phase", "magnitude_N", "peak_force_N", "pulse_hz", "duty", "shape", "dislodged",
                "event", "dislodge_time_s", "impulse_Ns", "applied_impulse_Ns", "objective_Ns", "increments",
                "newton_iterations", "settled", "retries", "wall_s"]


def run_case(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None) -> dict:
    """One study case of kind dislodging_beyond (see the module docstring)."""
    from mpi4py import MPI

    if scene["dim"] == 3:  # task 'pullout_3d', or its wedging prefix
        return run_3d(scene, case_dir, checkpoint, restart)
    case_dir, s, mu = Path(case_dir), scene["dislodging"], scene["contact"]["mu"]
    start = time.perf_counter()
    puller = BeyondPuller(scene, restart, case_dir / "checkpoint" if checkpoint else None)
    c = puller.contacts
    pullout = puller.pullout["quasi_static_pullout_N"]
    friction = mu * (c["N_A"] + c["N_B"])
    metrics = {**{f"wedged_{k}": v for k, v in c.items()}, "sum_normal_N": c["N_A"] + c["N_B"],
               "tilt_deg": math.degrees(puller.tilt), "one_dof_first_slip_N": puller.one_dof["first_slip"],
               "one_dof_full_slide_N": puller.one_dof["full_slide"], **puller.pullout,
               "degree_of_wedging": pullout / friction,
               "degree_of_wedging_rotation_held": puller.pullout.get("quasi_static_pullout_N_rotation_held", 0.0) / friction,
               "wedge_time_s": puller.wedge_time, "pullout_time_s": puller.pullout_time}
    info = {"dofs": puller.simulation.dofs, "effects": list(scene["effects"])}
    rows = []
    if len(scene["steps"]) > PULL_STEP and s["task"] == "threshold":
        metrics.update(puller.threshold(s["method"], rows, s["pulse_hz"], s["duty"], s["shape"]))
    elif len(scene["steps"]) > PULL_STEP and s["task"] == "optimise":
        optimum = optimise(puller, rows)
        optimum.update(verify(scene, restart, optimum))
        metrics.update({f"optimum_{k}": v for k, v in optimum.items()})
        if MPI.COMM_WORLD.rank == 0:
            from femcontact.io import write_json_atomic

            write_json_atomic(case_dir / "optimum.json", optimum)
    if rows and MPI.COMM_WORLD.rank == 0:
        with open(case_dir / "pulls.csv", "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=PULL_COLUMNS, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    metrics.update(pulls=len(rows), pull_wall_s=float(sum(row["wall_s"] for row in rows)))
    return {"metrics": metrics, "timings": {"wedge": puller.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}
