"""Ways out of a wedge in 2-D (kind "dislodging_methods"): loads at the peg top by method, and
the wedged peg pulled by any of them (`MethodPuller`, on the machinery of `pull.py`: the wedged
state computed once, implicit-Euler pulls that stop at the located event "dislodged",
thresholds by bisection).

Methods (`method_loads`): 'continuous' and 'pulse' (vertical pull), 'shake' (lateral pulses),
'twist' (moment pulses about the out-of-plane axis, magnitude F = M / d: the couple of two forces
F on the peg's top corners d apart), 'pull_shake' (a constant pull of `base_pull` x the pull-out
plus lateral pulses). Shake and twist act against the wedging moment (the other sense wedges the
peg harder). Reported: the peak force |F| (N; twist M / d) and the impulse |integral of F dt|
(N*s; twist the angular impulse / d) from the start of the pull to the event.
"""
import time

import numpy as np

from femcontact.families.dislodging.pull import OBSERVE_STEP, PULL_STEP, Puller
from femcontact.problem.loading import Schedule

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


class MethodPuller(Puller):
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

        s, sim = self.settings, self.simulation
        start = time.perf_counter()
        sim.resume(self.wedged)
        loads = self.set_loads(method, magnitude, frequency, duty, shape)
        outcome = sim.integrate([PULL_STEP, OBSERVE_STEP], Event(rise=s["rise"]), s["dt_max"], s["dt_min"],
                                s["max_rise_per_increment"],
                                settle_period=1 / frequency if method != "continuous" else 0.01)
        row = {"case": s["case"], "method": method, "magnitude_N": float(magnitude),
               "pulse_hz": frequency if method != "continuous" else "", "duty": duty if method != "continuous" else "",
               "shape": shape if method != "continuous" else "", "dislodged": outcome.event is not None,
               "event": outcome.event or "", "dislodge_time_s": "", "increments": outcome.increments,
               "newton_iterations": outcome.newton_iterations, "settled": outcome.settled,
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
