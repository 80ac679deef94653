"""Beyond the thesis' dislodging: degree of wedging, other ways out, pulse
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
- Peak-force optimisation: frequency and duty minimising the threshold peak force (a bisection
  per evaluation) for each shape, by bounded Nelder-Mead; the optimum re-run by a fresh
  simulation at its peak (dislodges) and one bracket below it (holds).
- 3-D: quasi-static thresholds of the wedged cylinder, by bisection: the force along its axis,
  the torque about the axis and the torque across it (against the wedging moment), all in the
  one process that wedged it (a checkpoint written on 2 ranks did not restore: the 3-D mesh was
  partitioned differently in the next process); every probe streamed to probes_3d.csv and read
  back when the case is run again; its 2-D estimates from the 3-D contact forces.
"""
import copy
import csv
import math
import time
from pathlib import Path

import numpy as np

from femcontact.io import read_csv
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
    from femcontact.solver.dynamics import step_impulse

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
        from femcontact.solver.dynamics import Event

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


def optimise_peak(puller: BeyondPuller, rows: list) -> dict:
    """Pulse (vertical pull) minimising the threshold peak force over frequency and duty, for
    each shape of `peak_shapes`: bounded Nelder-Mead (scipy) over (log10 Hz, duty) from the
    middle of the bounds (log scale in frequency), `peak_evaluations` evaluations per shape,
    each a bisection for the threshold peak (to `tolerance`). Every pull is appended to rows
    (column `phase`: the shape's evaluation number)."""
    from scipy.optimize import minimize

    s = puller.settings
    bounds = [tuple(np.log10(s["frequency_range"])), tuple(s["duty_range"])]
    x0 = np.array([np.mean(bounds[0]), np.mean(bounds[1])])
    simplex = np.clip([x0, x0 + [-0.5, 0.0], x0 + [0.0, 0.3]], *np.array(bounds).T)
    evaluations = []

    for shape in s["peak_shapes"]:
        cache = {}

        def fun(x, shape=shape, cache=cache):
            hz, duty = 10 ** x[0], float(x[1])
            key = (round(hz, 6), round(duty, 6))
            if key not in cache:
                mine = []
                found = puller.threshold("pulse", mine, key[0], key[1], shape)
                for row in mine:
                    row["phase"] = f"peak {len(evaluations) + 1}"
                rows.extend(mine)
                evaluations.append({"shape": shape, "pulse_hz": key[0], "duty": key[1], "pulls": len(mine), **found})
                cache[key] = found["threshold_force_N"]
            return cache[key]

        minimize(fun, x0, method="Nelder-Mead", bounds=bounds,
                 options={"maxfev": s["peak_evaluations"], "initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-6})
    best = min(evaluations, key=lambda e: e["threshold_force_N"])
    pullout = puller.pullout["quasi_static_pullout_N"]
    return {"shape": best["shape"], "pulse_hz": best["pulse_hz"], "duty": best["duty"],
            "objective_peak_force_N": best["threshold_force_N"], "peak_over_pullout": best["threshold_force_N"] / pullout,
            "bracket_N": best["bracket_N"], "impulse_at_threshold_Ns": best["impulse_at_threshold_Ns"],
            "dislodge_time_s": best["dislodge_time_at_threshold_s"], "evaluations": len(evaluations),
            "pulls": len(rows), "quasi_static_pullout_N": pullout, "all_evaluations": evaluations}


def verify_peak(scene: dict, restart, optimum: dict) -> dict:
    """The peak-force optimum re-run by a fresh simulation (new solver, state read from the
    checkpoint `restart`, or wedged again without one): the pulse at the optimal peak must
    dislodge and the same pulse one bisection bracket weaker must not."""
    fresh = BeyondPuller(copy.deepcopy(scene), restart)
    args = (optimum["pulse_hz"], optimum["duty"], optimum["shape"])
    at = fresh.run("pulse", optimum["objective_peak_force_N"], *args)
    below = fresh.run("pulse", optimum["objective_peak_force_N"] - optimum["bracket_N"], *args)
    return {"verified_dislodged": bool(at["dislodged"]), "verified_impulse_Ns": at["impulse_Ns"],
            "verified_below_holds": not below["dislodged"], "verified_below_peak_N": below["peak_force_N"]}


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


PROBE_COLUMNS = ["method", "magnitude", "holds", "newton_iterations", "residual_N", "moved_mm", "zone_A_N", "zone_B_N",
                 "reason", "wall_s"]
TWISTS_3D = {"continuous": "force (N) along the peg axis, out of the hole",
             "twist": "torque (N*mm) about the peg axis",
             "twist_across": "torque (N*mm) about the axis across the peg (perpendicular to it, in the plane of the "
                             "wedging moment's axis), against the wedging moment"}


class Wedge3D:
    """The wedged 3-D peg (quasi-static, no inertia) and its quasi-static thresholds: a force
    along its axis, a torque about it and a torque across it. Every probe is appended to the
    CSV file `probes` as it is solved; probes already in it are read back, not solved again
    (so a case stopped by its time limit resumes where it stopped, after wedging again)."""

    def __init__(self, scene: dict, restart=None, checkpoint=None, probes=None):
        from mpi4py import MPI

        self.scene, self.settings = scene, scene["dislodging"]
        self.simulation, self.wedge_time = wedged_simulation(scene, restart, checkpoint)
        sim = self.simulation
        rigid = sim.problem.rigid
        self.wedged_row, self.wedged = sim.history[-1], sim.snapshot()
        self.axis = rigid_axis(rigid)
        self.across = across_axis(scene["steps"][0]["moment"], self.axis)
        self.tilt = rigid.tilt()
        self.contacts = contacts_on_axis(self.wedged_row, self.axis, 3)
        self.comm = MPI.COMM_WORLD
        self.probes = Path(probes) if probes else None
        known = []
        if self.probes and self.comm.rank == 0 and self.probes.is_file():
            known = read_csv(self.probes)
        self.known = {(row["method"], round(float(row["magnitude"]), 6)): row["holds"] == "True"
                      for row in self.comm.bcast(known, root=0)}
        self.resumed = len(self.known)

    def direction(self, method: str) -> np.ndarray:
        """Unit vector of the force ('continuous') or torque of a method (global)."""
        return self.across if method == "twist_across" else self.axis

    def probe(self, magnitude: float, method: str) -> dict:
        """Does the wedge hold `magnitude` of `method` (TWISTS_3D) quasi-statically? Yes when the
        exact Newton iteration converges from the wedged state with both contact zones loaded
        and the peg moved by less than `lift` (mm: along the axis, or the rotation about the
        load's axis times the peg radius). Its row (PROBE_COLUMNS)."""
        from femcontact.solver.newton import NewtonFailure

        sim, s = self.simulation, self.settings
        start = time.perf_counter()
        sim.resume(self.wedged)
        pull = sim.scene["steps"][PULL_STEP]
        vector = list(magnitude * self.direction(method))
        pull.update(force=vector if method == "continuous" else [], moment=[] if method == "continuous" else vector,
                    amplitude="step", load_point="peg_top")
        sim.schedule = Schedule(sim.scene, sim.problem.rigid, sim.schedule.points)
        duration = pull["duration"]
        load = sim.schedule.load(PULL_STEP, duration, duration)
        r0 = self.wedged["state"]["r"]
        load.motion = r0.copy()
        row = {"method": method, "magnitude": float(magnitude), "reason": ""}
        try:
            row["newton_iterations"] = sim.solve(load, stabilize=False)
            converged = True
        except NewtonFailure as failure:
            converged = False
            history = failure.history or [float("nan")]
            row.update(newton_iterations=len(history) - 1, residual_N=history[-1],
                       reason=str(failure).split(";")[0])
        except (FloatingPointError, RuntimeError) as error:
            converged = False
            row.update(reason=type(error).__name__)
        zones = sim.zone_forces()  # of the last iterate: the converged state, or the last try
        row.update(holds=False, moved_mm="", zone_A_N=float(zones[0]), zone_B_N=float(zones[-1]))
        if converged:  # (a failed solve leaves the wedged state)
            r = sim.problem.rigid.values
            moved = (float(np.dot(r[:3] - r0[:3], self.axis)) if method == "continuous"
                     else float(np.dot(r[3:] - r0[3:], self.direction(method))) * self.scene["peg"]["width"] / 2)
            R_u, R_r, _ = sim.newton.current_residual(load)
            row.update(residual_N=sim.newton.norm(R_u, R_r), moved_mm=moved,
                       holds=bool(np.all(zones > 0) and abs(moved) < s["lift"]))
        row["wall_s"] = time.perf_counter() - start
        return row

    def holds(self, magnitude: float, method: str) -> bool:
        """`probe`, or its answer read back from the probes file; new probes are appended to it."""
        key = (method, round(magnitude, 6))
        if key not in self.known:
            row = self.probe(key[1], method)
            self.known[key] = row["holds"]
            if self.probes and self.comm.rank == 0:
                new = not self.probes.is_file()
                with open(self.probes, "a", newline="") as stream:
                    writer = csv.DictWriter(stream, fieldnames=PROBE_COLUMNS, extrasaction="ignore")
                    if new:
                        writer.writeheader()
                    writer.writerow(row)
        return self.known[key]

    def threshold(self, method: str, high: float) -> dict:
        """Largest magnitude the wedge holds, by bisection from [0, high] (high doubled until the
        wedge lets go, at most 4 times) to `tolerance` (N; torques: tolerance x the peg radius)."""
        tolerance = self.settings["tolerance"] * (self.scene["peg"]["width"] / 2 if method != "continuous" else 1.0)
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


def across_axis(wedging_moment, axis: np.ndarray) -> np.ndarray:
    """Unit axis across the peg (perpendicular to its `axis`) of the torque that turns it back
    out of its wedge: against the wedging moment (N*mm, global), as the 2-D twist."""
    m = -np.asarray(wedging_moment or [0.0, 0.0, 0.0], float)
    m = m - np.dot(m, axis) * axis
    if not np.linalg.norm(m) > 0:
        raise ValueError("the wedging moment has no component across the peg axis")
    return m / np.linalg.norm(m)


def rigid_axis(rigid) -> np.ndarray:
    """The peg axis (unit, global) at the current pose."""
    from femcontact.physics.rotation import rotation_numpy

    return rotation_numpy(rigid.split(rigid.values)[1]) @ rigid.Q0[:, -1]


PROBES_FILE = "probes_3d.csv"


def run_3d(scene: dict, case_dir: Path, checkpoint: bool, restart) -> dict:
    """Task 'pullout_3d' (or the 3-D wedging prefix): the wedged cylinder and its three
    quasi-static thresholds (TWISTS_3D), each probe streamed to `PROBES_FILE` in `case_dir`."""
    mu = scene["contact"]["mu"]
    start = time.perf_counter()
    wedge = Wedge3D(scene, restart, Path(case_dir) / "checkpoint" if checkpoint else None,
                    probes=Path(case_dir) / PROBES_FILE)
    c = wedge.contacts
    metrics = {**{f"wedged_{k}": v for k, v in c.items()}, "tilt_deg": math.degrees(wedge.tilt),
               "sum_normal_N": c["N_A"] + c["N_B"], "wedge_time_s": wedge.wedge_time,
               **{f"one_dof_{k}_N": v for k, v in one_dof_thresholds(**c, tilt=wedge.tilt, mu=mu).items()}}
    info = {"dofs": wedge.simulation.dofs, "effects": list(scene["effects"]), "probes_resumed": wedge.resumed}
    if len(scene["steps"]) <= PULL_STEP:
        return {"metrics": metrics, "timings": {"wedge": wedge.wedge_time}, "info": info}
    friction, radius = mu * metrics["sum_normal_N"], scene["peg"]["width"] / 2
    start_pull = time.perf_counter()
    pull = wedge.threshold("continuous", 2 * metrics["one_dof_first_slip_N"])  # the 2-D pull-out: ~first slip
    metrics.update(threshold_force_N=pull["threshold"], bracket_N=pull["bracket"], pull_solves=pull["solves"],
                   degree_of_wedging=pull["threshold"] / friction, pull_time_s=time.perf_counter() - start_pull)
    wedging = float(np.linalg.norm(scene["steps"][0]["moment"]))
    for method, prefix in (("twist", "twist"), ("twist_across", "across")):
        start_twist = time.perf_counter()
        twist = wedge.threshold(method, friction * radius)
        metrics.update({f"{prefix}_threshold_moment_Nmm": twist["threshold"], f"{prefix}_bracket_Nmm": twist["bracket"],
                        f"{prefix}_solves": twist["solves"],
                        f"{prefix}_over_friction_torque": twist["threshold"] / (friction * radius),
                        f"{prefix}_over_wedging_moment": twist["threshold"] / wedging,
                        f"{prefix}_time_s": time.perf_counter() - start_twist})
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
    elif len(scene["steps"]) > PULL_STEP and s["task"] == "optimise_peak":
        optimum = optimise_peak(puller, rows)
        optimum.update(verify_peak(scene, restart, optimum))
        metrics.update({f"optimum_{k}": v for k, v in optimum.items() if k != "all_evaluations"})
        if MPI.COMM_WORLD.rank == 0:
            from femcontact.io import write_json_atomic

            write_json_atomic(case_dir / "optimum_peak.json", optimum)
    if rows and MPI.COMM_WORLD.rank == 0:
        with open(case_dir / "pulls.csv", "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=PULL_COLUMNS, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    metrics.update(pulls=len(rows), pull_wall_s=float(sum(row["wall_s"] for row in rows)))
    return {"metrics": metrics, "timings": {"wedge": puller.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}
