"""Plot kinds of the compliant-insertion study (Whitney ch. 10; `metrics.py`).

- `insertion_history`: one panel per ok case, the FE force `y` (Fz, Fx or M) against the depth s
  with the FE phases shaded, the analytic tier's curve dashed on the same axes, and both
  two-point onsets marked;
- `jamming_diagram`: one panel per mu: Whitney's parallelogram in (F_x/F_z, M/(r F_z)) for a few
  lambda = l/(mu d), the FE two-point states coloured by their own lambda (a sliding state lies on
  the two-point side of its lambda), each case's last state marked inserted (o) or jammed (x);
- `wedging_window`: the tilt at two-point onset against the clearance ratio c, with the window
  c/mu < theta < sqrt(2c) where wedging is possible, cases marked wedged or not by the FE.
"""
import math
import re
from pathlib import Path

import numpy as np

from femcontact.io import read_csv

PHASE_COLOURS = {"chamfer": "tab:orange", "edge": "tab:purple", "one_point": "tab:green", "two_point": "tab:red"}


def case_curves(row: dict, results: Path):
    """(FE curve, analytic curve or None) of an ok insertion case, or None without its history."""
    from femcontact.families.insertion.metrics import analytic_curve, force_history

    path = results / "cases" / row["case_id"] / "history.csv"
    scene = row["scene"]
    if row["status"] != "ok" or not path.exists() or "compliant_support" not in scene.get("effects", []):
        return None
    curve = force_history(scene, read_csv(path, numbers=True))
    return curve, analytic_curve(scene, max(curve["depth"][-1], 1e-3))


def _label(scene: dict) -> str:
    peg, support = scene["peg"], scene["support"]
    rcc = f"RCC k {support['rcc']['k']:g}, " if support["model"] == "rcc" else ""
    rim = f"rim r {peg['corner_radius']:g}, " if peg["corner_radius"] > 0 else ""
    size = scene["mesh"]["contact_size"]
    mesh = f", h_c {size:g} mm" if size > 0 else ""  # the contact elements' size
    return (f"{scene['dim']}-D, {rcc}{rim}eps0 {peg['offset']:g}, th0 {peg['tilt']:g} deg, L_g {support['compliance_centre']:g}, "
            f"mu {scene['contact']['mu']:g}, D {scene['hole']['width']:g}, E {scene['materials']['hole']['E']:g}{mesh}")


def _file(spec: dict, default: str) -> str:
    return spec["file"] or re.sub(r"[^\w.-]+", "_", default) + ".png"


def write_insertion_history(spec: dict, rows: list[dict], results: Path, column) -> Path:
    import matplotlib.pyplot as plt
    from femcontact.families.insertion.metrics import two_point_onset

    quantity = spec["y"] if spec["y"] in ("Fz", "Fx", "M") else "Fz"
    cases = [(row, c) for row in rows if (c := case_curves(row, results)) is not None]
    n = max(len(cases), 1)
    cols = min(3, n)
    figure, axes = plt.subplots((n + cols - 1) // cols, cols, figsize=(5.2 * cols, 3.6 * ((n + cols - 1) // cols)),
                                squeeze=False)
    for panel, (row, (curve, analytic)) in zip(axes.flat, cases):
        depth = np.array(curve["depth"])
        for phase, colour in PHASE_COLOURS.items():
            mask = np.array([ph == phase for ph in curve["phase"]])
            if mask.any():
                panel.fill_between(depth, 0, 1, where=mask, color=colour, alpha=0.15, step="mid",
                                   transform=panel.get_xaxis_transform(), label=f"FE {phase}")
        panel.plot(depth, curve[quantity], "k-", lw=1.5, label=f"FE {quantity}")
        onset = two_point_onset(curve)
        if onset is not None:
            panel.axvline(onset, color="tab:red", lw=1, label="FE two-point onset")
        if analytic is not None:
            panel.plot(analytic["depth"], analytic[quantity], "--", color="tab:blue", lw=1.2, label=f"analytic {quantity}")
            if analytic["two_point_onset"] is not None:
                panel.axvline(analytic["two_point_onset"], color="tab:blue", ls=":", lw=1, label="analytic onset")
        if bool(column(row, "jammed")):
            panel.text(0.02, 0.9, "FE: jammed", transform=panel.transAxes, color="tab:red")
        panel.set_title(_label(row["scene"]), fontsize=7)
        panel.set_xlabel("depth s below the chamfer's lower edge (mm)")
        panel.set_ylabel(f"{quantity} ({'N*mm' if quantity == 'M' else 'N'})")
        top = max([abs(v) for v in curve[quantity]] + [1e-9])
        if analytic is not None:
            top = max([top] + [abs(v) for v in analytic[quantity]])
        if top > 50 * max(abs(v) for v in curve[quantity][len(curve[quantity]) // 2:] + [1e-9]):
            panel.set_yscale("symlog", linthresh=1.0)
        panel.grid(alpha=0.3)
    for panel in list(axes.flat)[len(cases):]:
        panel.axis("off")
    if cases:
        axes.flat[0].legend(fontsize=6)
    figure.suptitle(spec["title"] or f"Insertion force history: FE (solid) and analytic (dashed), {quantity}")
    figure.tight_layout(rect=(0, 0, 1, 0.98))
    path = results / _file(spec, f"insertion_history_{quantity}")
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def write_jamming_diagram(spec: dict, rows: list[dict], results: Path, column) -> Path:
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors
    from femcontact.references import whitney

    cases = [(row, c) for row in rows if (c := case_curves(row, results)) is not None
             and any(ph == "two_point" for ph in c[0]["phase"])]
    mus = sorted({row["scene"]["contact"]["mu"] for row, _ in cases}) or [0.1]
    figure, axes = plt.subplots(1, len(mus), figsize=(6 * len(mus), 5.5), squeeze=False)
    top = max([4.0] + [l / (row["scene"]["contact"]["mu"] * row["scene"]["peg"]["width"])
                       for row, (curve, _) in cases for l, ph in zip(curve["l"], curve["phase"]) if ph == "two_point"])
    norm = colors.Normalize(0.0, min(top, 20.0))
    colour = cm.viridis
    for panel, mu in zip(axes.flat, mus):
        for lam in np.linspace(norm.vmax / 4, norm.vmax, 4):
            corners = whitney.jamming_corners(lam, mu)
            panel.plot(*np.vstack([corners, corners[:1]]).T, lw=1, color=colour(norm(lam)))
        counts = {True: 0, False: 0}
        for row, (curve, _) in cases:
            if row["scene"]["contact"]["mu"] != mu:
                continue
            r, d = row["scene"]["peg"]["width"] / 2, row["scene"]["peg"]["width"]
            states = [i for i, ph in enumerate(curve["phase"]) if ph == "two_point" and abs(curve["Fz"][i]) > 1e-9]
            x = np.array([curve["Fx"][i] / curve["Fz"][i] for i in states])
            y = np.array([curve["M"][i] / (r * curve["Fz"][i]) for i in states])
            lam = np.array([curve["l"][i] / (mu * d) for i in states])
            panel.scatter(x, y, c=lam, cmap=colour, norm=norm, s=10)
            is_jammed = bool(column(row, "jammed"))
            counts[is_jammed] += 1
            panel.plot(x[-1], y[-1], "x" if is_jammed else "o", color="tab:red", markersize=10,
                       markerfacecolor="none", linestyle="none")
        panel.plot([], [], "o", color="tab:red", markerfacecolor="none", label=f"last state, FE inserted ({counts[False]})")
        panel.plot([], [], "x", color="tab:red", label=f"last state, FE jammed ({counts[True]})")
        panel.set(xlabel="F_x / F_z", ylabel="M / (r F_z)  (M about the tip)", title=f"mu = {mu:g}")
        panel.set_xlim(-1.2 / mu, 1.2 / mu)
        panel.grid(alpha=0.3)
        panel.legend(fontsize=7)
    figure.colorbar(cm.ScalarMappable(norm=norm, cmap=colour), ax=list(axes.flat), label="lambda = l / (mu d)")
    figure.suptitle(spec["title"] or "Jamming diagram: parallelograms (colour = lambda) and the FE two-point "
                    "states (dots, colour = their lambda)", fontsize=9)
    path = results / _file(spec, "jamming_diagram")
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def write_wedging_window(spec: dict, rows: list[dict], results: Path, column) -> Path:
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(7, 5))
    points = []
    for row in rows:
        curves = case_curves(row, results)
        if curves is None:
            continue
        curve = curves[0]
        first = next((i for i, ph in enumerate(curve["phase"]) if ph == "two_point"), None)
        if first is None:
            continue
        scene = row["scene"]
        c = (scene["hole"]["width"] - scene["peg"]["width"]) / scene["hole"]["width"]
        points.append((c, abs(math.radians(curve["theta"][first])), scene["contact"]["mu"],
                       bool(column(row, "wedged"))))
    cs = np.linspace(1e-4, max([p[0] for p in points] + [0.01]) * 1.3, 200)
    axes.plot(cs, np.sqrt(2 * cs), "k-", label="theta_m = sqrt(2c): largest entering tilt")
    for mu in sorted({p[2] for p in points}) or [0.1]:
        line, = axes.plot(cs, cs / mu, "--", label=f"theta_W = c/mu (mu {mu:g})")
        axes.fill_between(cs, cs / mu, np.sqrt(2 * cs), where=cs / mu < np.sqrt(2 * cs), alpha=0.08,
                          color=line.get_color())
        for wedged in (False, True):
            chosen = [(p[0], p[1]) for p in points if p[3] == wedged and p[2] == mu]
            if chosen:
                axes.plot(*zip(*chosen), "s" if wedged else "o", color=line.get_color(), markersize=8,
                          markerfacecolor=line.get_color() if wedged else "none", linestyle="none",
                          label=f"FE {'wedged (filled)' if wedged else 'not wedged'}, mu {mu:g} ({len(chosen)})")
    axes.set(xlabel="clearance ratio c = (D - d)/D", ylabel="tilt at two-point onset (rad)",
             title=spec["title"] or "Wedging window c/mu < theta < sqrt(2c) and the FE cases", yscale="log")
    axes.grid(alpha=0.3)
    axes.legend(fontsize=7)
    path = results / _file(spec, "wedging_window")
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
