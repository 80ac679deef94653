"""Snap-fit plot kinds of `femcontact report` (the snap_fit family's `plots`) and its summary table:

- `force_curves`: a list metric against another (insertion_force against insertion_depth, or
  the withdrawal pair) for the cases `select` picks, one curve per case labelled by `series`,
  with the reduced rigid-arm model of the same scene dashed beside each;
- `sweep`: a scalar metric (FE, markers) against a swept key for the cases `select` picks, with
  the reduced model's `model_<metric>` as a line when the cases have it;
- `jam_map`: simulated jammed / sliding cases (those `select` picks) in the plane of the nose angle (x) and mu (y),
  with Whitney's friction-cone bound alpha + phi = 90 deg and the reduced model's bound
  1.5 (e/L) tan(alpha + phi) = 1.

The report passes its `column(row, name)` (a row's metric or scene value) to each function.
"""
import math
import re
from pathlib import Path

import numpy as np

from femcontact.config.scene import friction_coefficient
from femcontact.outputs.tables import format_value


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _selected(row: dict, select: dict, column) -> bool:
    return all(column(row, key) in (value if isinstance(value, list) else [value]) for key, value in select.items())


def model_curve(scene: dict, depth, withdrawal: bool = False) -> np.ndarray:
    """Reduced-model axial force (N, all springs) at the given depths for a resolved scene;
    for withdrawal, the pull force (-F_ax)."""
    from femcontact.references import snap_fit as reference
    from geometry.snap_fit import layout, nose_profile

    spring, material = scene["spring"], scene["materials"]["spring"]
    mu = friction_coefficient(scene)
    k = reference.cantilever_stiffness(material["E"], spring["thickness"], spring["length"], spring["width"])
    _, axial = reference.rigid_arm_forces(nose_profile(scene["peg"]), layout(scene).apex[0], k, mu,
                                          reference.coupling(spring), np.asarray(depth), withdrawal)
    return spring["count"] * (-axial if withdrawal else axial)


def _label(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def write_force_curves(spec: dict, rows: list[dict], results: Path, column) -> Path:
    plt = _figure()
    figure, axes = plt.subplots(figsize=(7.0, 4.6), layout="constrained")
    withdrawal = spec["y"].startswith("withdrawal")
    ends = []  # where each curve settles to its value on the shank
    for index, row in enumerate(r for r in rows if r["status"] == "ok" and _selected(r, spec["select"], column)):
        depth, force = column(row, spec["x"]), column(row, spec["y"])
        if not isinstance(depth, list) or not isinstance(force, list):
            continue
        label = _label(column(row, spec["series"])) if spec["series"] else row["case_id"]
        colour = f"C{index % 10}"
        changing = [d for d, f in zip(depth, force) if abs(f - force[-1]) > 1e-3 * max(map(abs, force))]
        ends.append(max(changing, default=max(depth)))
        axes.plot(depth, force, "o-", color=colour, markersize=3, label=f"FE: {label}")
        grid = np.linspace(min(depth), max(depth), 300)
        axes.plot(grid, model_curve(row["scene"], grid, withdrawal), "--", color=colour, linewidth=1,
                  label=f"rigid-arm model: {label}")
    if ends:
        axes.set_xlim(right=1.25 * max(ends))
    axes.set(xlabel=f"{spec['x']} (mm)", ylabel=f"{spec['y']} (N)", title=spec["title"] or f"{spec['y']} against depth")
    axes.title.set_fontsize(9)
    return _save(plt, figure, axes, results, spec, f"{spec['y']}_curves", legend_size=7)


def _save(plt, figure, axes, results: Path, spec: dict, default_name: str, legend_size: int = 8) -> Path:
    """Grid, legend, then the PNG (the spec's file name, or a name made from `default_name`)."""
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=legend_size)
    path = results / (spec["file"] or re.sub(r"[^\w.-]+", "_", default_name) + ".png")
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def write_sweep(spec: dict, rows: list[dict], results: Path, column) -> Path:
    plt = _figure()
    figure, axes = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    chosen = sorted((column(r, spec["x"]), r) for r in rows if r["status"] == "ok" and _selected(r, spec["select"], column))
    x = [c[0] for c in chosen]
    axes.plot(x, [column(r, spec["y"]) for _, r in chosen], "o-", label=f"FE: {spec['y']}")
    model = [column(r, f"model_{spec['y']}") for _, r in chosen]
    if model and all(isinstance(v, (int, float)) for v in model):
        axes.plot(x, model, "k--", label="rigid-arm model")
    axes.set(xlabel=spec["x"], ylabel=spec["y"], title=spec["title"] or f"{spec['y']} against {spec['x']}",
             xscale="log" if spec["logx"] else "linear", yscale="log" if spec["logy"] else "linear")
    return _save(plt, figure, axes, results, spec, f"{spec['y']}_vs_{spec['x']}")


def write_jam_map(spec: dict, rows: list[dict], results: Path, column) -> Path:
    from femcontact.references import snap_fit as reference

    plt = _figure()
    figure, axes = plt.subplots(figsize=(6.4, 5.4), layout="constrained")
    marks = {True: ("x", "tab:red", "FE: jammed"), False: ("o", "tab:green", "FE: slides")}
    seen, couples = set(), []
    rows = [r for r in rows if _selected(r, spec["select"], column)]
    for row in rows:
        x, y = column(row, spec["x"]), column(row, spec["y"])
        if row["status"] != "ok":
            axes.plot(x, y, "s", color="0.6", markersize=6, label=None if "failed" in seen else "FE: failed")
            seen.add("failed")
            continue
        jammed = bool(column(row, "jammed"))
        marker, colour, label = marks[jammed]
        axes.plot(x, y, marker, color=colour, markersize=8, label=None if jammed in seen else label)
        seen.add(jammed)
        couples.append(reference.coupling(row["scene"]["spring"]))
    couple = max(set(couples), key=couples.count) if couples else None  # the most common spring
    mu = np.linspace(0.01, 1.0, 200)
    axes.plot(90 - np.degrees(np.arctan(mu)), mu, "k-", label="friction cone: alpha + phi = 90 deg")
    if couple:
        axes.plot(np.degrees(np.arctan(1 / couple)) - np.degrees(np.arctan(mu)), mu, "k--",
                  label=f"reduced model: 1.5 (e/L) tan(alpha + phi) = 1 (1.5 e/L = {couple:.3g})")
    axes.set(xlabel="nose angle alpha from the insertion axis (deg)", ylabel="mu",
             title=spec["title"] or "Jamming: nose angle against friction")
    axes.set_ylim(0, max(0.6, max((column(r, spec["y"]) or 0) for r in rows) * 1.1) if rows else 1.0)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    path = results / (spec["file"] or "jam_map.png")
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def table(rows: list[dict], column) -> list[tuple]:
    """Report blocks: the nose shapes' peak insertion force, FE against the reduced model, and the
    change against the flat taper (the cases whose scene name starts with `nose_`; the taper is
    `nose_taper`)."""
    cases = [r for r in rows if r["status"] == "ok" and str(column(r, "name")).startswith("nose_")]
    if not cases:
        return []
    taper = next((r for r in cases if column(r, "name") == "nose_taper"), None)
    header = ["design", "nose", "final contact force (N)", "peak insertion (N) FE", "model", "vs taper (FE)",
              "peak withdrawal (N)", "root stress / yield", "max FE stress / yield"]
    body = []
    for r in cases:
        saving = (1 - column(r, "peak_insertion_force") / column(taper, "peak_insertion_force")) if taper else math.nan
        body.append([format_value(v) for v in (
            column(r, "name")[5:], column(r, "peg.nose"), column(r, "final_contact_force"),
            column(r, "peak_insertion_force"), column(r, "model_peak_insertion_force"),
            f"{-100 * saving:+.1f} %" if taper else "", column(r, "peak_withdrawal_force"),
            column(r, "root_yield_ratio"), column(r, "yield_ratio"))])
    return [("h2", "Nose shapes at equal final contact force"), ("table", header, body)]
