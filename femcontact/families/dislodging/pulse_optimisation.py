"""Pulse optimisation of a wedged 2-D peg (tasks 'optimise' and 'optimise_peak' of kind
"dislodging_methods").

- Least impulse: frequency, duty, shape and peak force minimising the impulse to dislodge: a grid
  over frequency x duty per shape, then bounded Nelder-Mead (scipy) from the best grid point of
  each shape; the optimum re-run by a fresh simulation from the checkpoint.
- Least peak force: frequency and duty minimising the threshold peak force (a bisection per
  evaluation) for each shape, by bounded Nelder-Mead; the optimum re-run by a fresh simulation at
  its peak (dislodges) and one bracket below it (holds).
"""
import copy
import math

import numpy as np

from femcontact.families.dislodging.methods import MethodPuller
from femcontact.families.dislodging.scene import SHAPES


def objective(row: dict) -> float:
    """Impulse to dislodge (N*s); a pull that holds scores twice the impulse it applied over
    the whole pull step (worse than any pull that dislodges with it)."""
    return float(row["impulse_Ns"]) if row["dislodged"] else 2.0 * float(row["applied_impulse_Ns"])


def optimise(puller: MethodPuller, rows: list) -> dict:
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
    fresh = MethodPuller(copy.deepcopy(scene), restart)
    row = fresh.run("pulse", optimum["peak_force_N"], optimum["pulse_hz"], optimum["duty"], optimum["shape"])
    impulse = objective(row)
    return {"verified_impulse_Ns": impulse, "verified_dislodged": bool(row["dislodged"]),
            "verified_relative_difference": abs(impulse - optimum["objective_impulse_Ns"]) / optimum["objective_impulse_Ns"]}


def optimise_peak(puller: MethodPuller, rows: list) -> dict:
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
    fresh = MethodPuller(copy.deepcopy(scene), restart)
    args = (optimum["pulse_hz"], optimum["duty"], optimum["shape"])
    at = fresh.run("pulse", optimum["objective_peak_force_N"], *args)
    below = fresh.run("pulse", optimum["objective_peak_force_N"] - optimum["bracket_N"], *args)
    return {"verified_dislodged": bool(at["dislodged"]), "verified_impulse_Ns": at["impulse_Ns"],
            "verified_below_holds": not below["dislodged"], "verified_below_peak_N": below["peak_force_N"]}
