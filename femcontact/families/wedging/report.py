"""The wedging family's report: the wedge map (plot kind `wedge_map`) and the agreement table.

The report passes its `column(row, name)` (a row's metric or scene value) to each function.
"""
import math
import re
import textwrap
from pathlib import Path

from femcontact.errors import InputError
from femcontact.io import write_atomic
from femcontact.outputs import units
from femcontact.outputs.figures import plain_log_ticks
from femcontact.outputs.result import ANSWERS


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def write_wedge_map(spec: dict, rows: list[dict], results: Path, column) -> Path:
    """Simulated wedged / not wedged (filled circle / cross; green when it agrees with the analytic
    condition l_crit <= l_d <= mu d, red when not) in the plane of two columns, with the analytic
    bounds drawn: x = 1 and y = 1 for the normalised map (depth_over_l_crit, depth_over_l_max);
    for y = peg.insertion_depth against clearance_ratio or contact.mu, the curves l_crit and
    l_max = mu d for the most common peg width (other widths are left out), one per value of the
    parameter not on the axis. Needs the metrics `wedged` and `analytic_wedged` (`metrics.py`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    x, y = spec["x"], spec["y"]
    points = []
    for row in rows:
        if row["status"] not in ANSWERS:  # a load without equilibrium answers: not wedged
            continue
        xv, yv, wedged, analytic = column(row, x), column(row, y), column(row, "wedged"), column(row, "analytic_wedged")
        if all(isinstance(v, (int, float)) for v in (xv, yv, wedged, analytic)) and math.isfinite(yv):
            points.append((xv, yv, bool(wedged), bool(analytic), row))
    physical = y == "peg.insertion_depth" and x in ("clearance_ratio", "contact.mu")
    if physical and points:
        widths = [column(p[4], "peg.width") for p in points]
        d = max(set(widths), key=widths.count)
        points = [p for p, w in zip(points, widths) if w == d]
    if rows and not points:
        raise InputError(f"[[plot]] wedge_map {y} against {x}: no ok case has numbers for both and the metrics "
                         "wedged, analytic_wedged")
    figure, axes = plt.subplots(figsize=(9, 5), layout="constrained")
    for wedged, marker, label in ((True, "o", "simulated: wedged"), (False, "x", "simulated: not wedged")):
        for agree, colour in ((True, "tab:green"), (False, "tab:red")):
            chosen = [(p[0], p[1]) for p in points if p[2] == wedged and (p[2] == p[3]) == agree]
            if chosen:
                axes.plot(*zip(*chosen), marker, color=colour, markersize=7, linestyle="none",
                          label=f"{label} ({'agrees' if agree else 'disagrees'})")
    if x == "depth_over_l_crit" or y == "depth_over_l_max":
        if x == "depth_over_l_crit":
            axes.axvline(1.0, color="k", linestyle="--", label="l_d = l_crit")
        if y == "depth_over_l_max":
            axes.axhline(1.0, color="k", linestyle=":", label="l_d = mu d")
    elif physical and points:
        xs = np.array([p[0] for p in points])
        grid = np.linspace(0.0, xs.max() * 1.15, 200)[1:]
        if x == "clearance_ratio":
            axes.plot(grid, d * np.sqrt(1 / (1 - grid) ** 2 - 1), "k--", label="l_crit(c)")
            for mu in sorted({column(p[4], "contact.mu") for p in points}):
                axes.axhline(mu * d, color="k", linestyle=":", label=f"l_max = mu d (mu = {mu:g})")
                axes.annotate(f"mu = {mu:g}", (1.0, mu * d), xycoords=("axes fraction", "data"), xytext=(-3, 2),
                              textcoords="offset points", ha="right", va="bottom", fontsize=7,
                              annotation_clip=True)
        else:
            axes.plot(grid, grid * d, "k:", label="l_max = mu d")
            for D in sorted({column(p[4], "hole.width") for p in points}):
                axes.axhline(math.sqrt(D * D - d * d), color="k", linestyle="--", label=f"l_crit (D = {D:g})")
                axes.annotate(f"l_crit, D = {D:g}", (1.0, math.sqrt(D * D - d * d)), xycoords=("axes fraction", "data"),
                              xytext=(-3, 2), textcoords="offset points", ha="right", va="bottom", fontsize=7,
                              annotation_clip=True)
        axes.set_ylim(0, max(p[1] for p in points) * 1.15)
    agree = sum(p[2] == p[3] for p in points)
    axes.set(xlabel=units.label(x), ylabel=units.label(y),
             xscale="log" if spec["logx"] else "linear", yscale="log" if spec["logy"] else "linear")
    title = spec["title"] or f"wedge map: {units.label(y)} against {units.label(x)}"
    axes.set_title(textwrap.fill(title, 60) + f"\nagreement with the analytic condition: {agree}/{len(points)}",
                   fontsize=11)
    plain_log_ticks(axes, spec)
    axes.grid(True, alpha=0.3)
    if points:
        axes.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    path = results / (spec["file"] or re.sub(r"[^\w.-]+", "_", f"wedge_map_{y}_vs_{x}") + ".png")
    write_atomic(path, lambda stream: figure.savefig(stream, format="png", dpi=120), binary=True)
    plt.close(figure)
    return path


def wedge_table(rows: list[dict], column) -> list[tuple]:
    """Summary blocks: agreement of the simulated `wedged` with `analytic_wedged`, overall, away from
    the bounds and near them (`near_boundary`), and the disagreeing cases. None without those metrics."""
    cases = [row for row in rows if row["status"] == "ok"
             and _number(column(row, "wedged")) and _number(column(row, "analytic_wedged"))]
    if not cases:
        return []

    def rate(subset):
        n = len(subset)
        k = sum(bool(column(r, "wedged")) == bool(column(r, "analytic_wedged")) for r in subset)
        return f"{k}/{n}" + (f" ({100 * k / n:.0f} %)" if n else "")

    near = [r for r in cases if column(r, "near_boundary")]
    far = [r for r in cases if not column(r, "near_boundary")]
    blocks = [("h2", "Wedge map: simulated against l_crit <= l_d <= mu d"),
              ("table", ["cases", "agree"], [["all", rate(cases)], ["away from the bounds", rate(far)],
                                             ["near a bound (within 5 % of mu d)", rate(near)]])]
    wrong = [r for r in cases if bool(column(r, "wedged")) != bool(column(r, "analytic_wedged"))]
    if wrong:
        names = ["case_id", "peg.width", "hole.width", "contact.mu", "peg.insertion_depth", "l_crit", "l_max",
                 "wedged", "wedge_reason", "residual_force_A"]
        blocks += [("p", "Disagreements:"),
                   ("table", [units.label(n) for n in names], [[units.cell(column(r, n), n) for n in names] for r in wrong])]
    return blocks
