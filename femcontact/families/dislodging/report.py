"""The report of a dislodging study (kind "dislodging", the thesis' pulls): thresholds against the
thesis', the pulls' tables and the impulse plots, written by `femcontact report`."""
import csv
import math
from pathlib import Path

import numpy as np

from femcontact.families.repository import ROOT
from femcontact.io import read_csv, read_result
from femcontact.families.dislodging.pull import PULLOUT_SUFFIX, pull_columns
THESIS_THRESHOLDS = {  # (case, method, Hz): (highest force not dislodged, lowest dislodged) in N,
    # from tests/data/dislodging_thesis.csv (thesis ch. 4); None: every sampled force dislodged
    (1, "continuous", 0.0): (None, 20.2), (1, "pulse", 10.0): (20.28, 20.29), (1, "pulse", 20.0): (20.22, 20.23),
    (1, "pulse", 30.0): (20.2, 20.21), (1, "pulse", 40.0): (None, 20.2), (1, "pulse", 50.0): (None, 20.2),
    (2, "continuous", 0.0): (None, 22.5), (2, "pulse", 10.0): (22.66, 22.67), (2, "pulse", 20.0): (22.6, 22.61),
    (2, "pulse", 30.0): (22.57, 22.58), (2, "pulse", 40.0): (22.55, 22.56), (2, "pulse", 50.0): (22.5, 22.55),
}
THRESHOLD_COLUMNS = ["case", "method", "pulse_hz", "rotation", "thickness_mm", "threshold_force_N", "bracket_N",
                     "quasi_static_pullout_N", "impulse_at_threshold_Ns", "time_at_threshold_s", "threshold_over_pullout",
                     "one_dof_first_slip_N",
                     "one_dof_full_slide_N", "quasi_static_pullout_N_rotation_held", "thesis_threshold_N",
                     "thesis_over_thesis_continuous"]


def _number(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def gather(study) -> tuple[list[dict], list[dict]]:
    """The study's pull rows and threshold rows (from the ok case directories)."""

    pulls, thresholds = [], []
    for case in study.cases:
        result = read_result(case.dir)
        if not result or result["status"] != "ok":
            continue
        s, metrics = case.scene["dislodging"], result["metrics"]
        if (case.dir / "pulls.csv").exists():
            pulls += read_csv(case.dir / "pulls.csv", comments=True)
        if "threshold_force_N" in metrics:
            hz = s["pulse_hz"] if s["method"] == "pulse" else 0.0
            pullout = metrics["quasi_static_pullout_N" + PULLOUT_SUFFIX[s["rotation"]]]
            thresholds.append({"case": s["case"], "method": s["method"], "pulse_hz": hz if hz else "", "rotation": s["rotation"],
                               "thickness_mm": s["thickness"], "quasi_static_pullout_N": pullout,
                               "quasi_static_pullout_N_rotation_held": metrics.get("quasi_static_pullout_N_rotation_held", ""),
                               "one_dof_first_slip_N": metrics["one_dof_first_slip_N"],
                               "one_dof_full_slide_N": metrics["one_dof_full_slide_N"],
                               "threshold_over_pullout": metrics["threshold_force_N"] / pullout,
                               **{k: metrics[k] for k in ("threshold_force_N", "bracket_N", "impulse_at_threshold_Ns")}})
    for row in thresholds:
        hz = _number(row["pulse_hz"]) or 0.0
        thesis = THESIS_THRESHOLDS.get((row["case"], row["method"], hz), (None, None))[1]
        reference = THESIS_THRESHOLDS.get((row["case"], "continuous", 0.0), (None, None))[1]
        row["thesis_threshold_N"] = thesis if thesis is not None else ""
        row["thesis_over_thesis_continuous"] = thesis / reference if thesis and reference else ""
        at_threshold = [pull for pull in pulls if int(pull["case"]) == row["case"] and pull["method"] == row["method"]
                        and (_number(pull["pulse_hz"]) or 0.0) == hz and pull["dislodged"] == "True"
                        and _number(pull["thickness_mm"]) == row["thickness_mm"]
                        and math.isclose(float(pull["force_N"]), row["threshold_force_N"], rel_tol=1e-6)]
        row["time_at_threshold_s"] = float(at_threshold[0]["dislodge_time_s"]) if at_threshold else ""
    key = lambda r: (int(r["case"]), r["method"], _number(r["pulse_hz"]) or 0.0, _number(r.get("force_N")) or 0.0)
    return sorted(pulls, key=key), sorted(thresholds, key=key)


def render_snapshots(study) -> list[Path]:
    """snapshots/caseN_wedged.png (von Mises at the wedged state) and caseN_METHOD_before_event.png
    (the threshold pull at the start of the increment in which the peg lets go) for the
    continuous pull and the 50 Hz pulses (1 mm), zoomed on contact A; skipped without fields."""
    from femcontact.io import make_dir
    from femcontact.outputs import snapshot

    paths, done = [], set()
    for case in study.cases:
        s = case.scene["dislodging"]
        result = read_result(case.dir)
        if not result or result["status"] != "ok" or s["thickness"] != 1.0:
            continue
        method = "continuous" if s["method"] == "continuous" else f"{s['pulse_hz']:g}Hz"
        wanted = [("wedged", f"case{s['case']}_wedged")]
        if method in ("continuous", "50Hz"):
            wanted.append(("before_event", f"case{s['case']}_{method}_before_event"))
        for state, name in wanted:
            fields = case.dir / state / "fields.npz"
            if name in done or not fields.exists():
                continue
            path = make_dir(study.results / "snapshots") / f"{name}.png"
            snapshot.render(fields, path, zoom="contact_A", zoom_radius=4.0)
            done.add(name)
            paths.append(path)
    return paths


SUMMARY_COLUMNS = (["threshold_force_N", "bracket_N", "impulse_at_threshold_Ns", "time_at_threshold_s",
                    "threshold_over_pullout", "quasi_static_pullout_N", "thesis_threshold_N",
                    "thesis_over_thesis_continuous", "case", "method", "pulse_hz", "rotation", "thickness_mm"])
"""The thresholds table at the head of the study's summary: the answer first, then the case."""


def summary_blocks(study) -> list[tuple]:
    """Report blocks: the thresholds table (one row per pull method and case; see SUMMARY_COLUMNS)."""
    from femcontact.outputs import units

    _, thresholds = gather(study)
    if not thresholds:
        return []
    return [("h2", "Thresholds: the least pull that dislodges the peg"),
            ("p", "Each method's threshold pull (bisection, within the bracket), the impulse and time it takes to "
                  "dislodge the peg at that pull, its ratio to the quasi-static pull-out, and the thesis' threshold "
                  "with its ratio to the thesis' continuous one (thresholds.csv has every column)."),
            ("table", [units.label(name) for name in SUMMARY_COLUMNS],
             [[units.format_value(row[name]) for name in SUMMARY_COLUMNS] for row in thresholds])]


FRAME_COLUMNS = ["case", "method", "pulse_hz", "rotation", "force_N", "thesis_frame", "frame", "dislodge_time_s",
                 "frame_difference", "within_one_frame", "thesis_impulse_Ns", "impulse_frames_Ns"]


def thesis_frames(pulls: list[dict], thesis: list[dict], frame: float = 0.005) -> list[dict]:
    """Row-by-row comparison with the thesis' table: every thesis cell (case, method, frequency,
    force) that one of our pulls ran at the same force (to 1e-6 N). Our frame is ceil(t / frame),
    frames numbered from the start of the pull (frame k ends at k x 0.005 s, the convention of the
    thesis' 50 Hz cells); "" where one side did not dislodge. `within_one_frame`: both dislodged
    within one frame of each other, or neither did."""
    out = []
    for ours in pulls:
        method = "pulsed" if ours["method"] == "pulse" else "continuous"
        hz = "" if method == "continuous" else f"{float(ours['pulse_hz']):g}"
        match = [r for r in thesis if int(r["case"]) == int(ours["case"]) and r["method"] == method
                 and r["pulse_hz"] == hz and abs(float(r["force_N"]) - float(ours["force_N"])) < 1e-6]
        if not match:
            continue
        theirs = int(match[0]["dislodge_frame"]) if match[0]["dislodge_frame"] else None
        mine = math.ceil(float(ours["dislodge_time_s"]) / frame - 1e-9) if ours["dislodged"] in (True, "True") else None
        both = theirs is not None and mine is not None
        out.append({**{k: ours[k] for k in ("case", "method", "pulse_hz", "rotation", "force_N", "dislodge_time_s",
                                             "impulse_frames_Ns")},
                    "thesis_frame": theirs if theirs is not None else "", "frame": mine if mine is not None else "",
                    "frame_difference": mine - theirs if both else "",
                    "within_one_frame": (abs(mine - theirs) <= 1) if both else (theirs is None and mine is None),
                    "thesis_impulse_Ns": match[0]["impulse_Ns"]})
    return out


def absolute_impulse_plots(pulls: list[dict], thesis: list[dict], out: Path) -> list[Path]:
    """caseN_impulse_vs_force_N.png: the frame-quantised impulse (and the exact one, dotted) of our
    dislodging pulls against the peak force in N, beside the thesis' cells of the same method
    (its Figures 4-7 to 4-10 on one plot): for a model whose thresholds are the thesis' own."""
    import matplotlib.pyplot as plt

    paths = []
    for case in sorted({int(r["case"]) for r in pulls}):
        fig, ax = plt.subplots(figsize=(8, 5))
        mine = [r for r in pulls if int(r["case"]) == case and r["dislodged"] == "True"]
        series = sorted({(r["method"], _number(r["pulse_hz"]) or 0.0, r.get("rotation") or "free") for r in mine})
        for k, (method, hz, rotation) in enumerate(series):
            rows = sorted((r for r in mine if (r["method"], _number(r["pulse_hz"]) or 0.0, r.get("rotation") or "free")
                           == (method, hz, rotation)), key=lambda r: float(r["force_N"]))
            name = "continuous" if method == "continuous" else f"{hz:g} Hz"
            force = [float(r["force_N"]) for r in rows]
            ax.plot(force, [float(r["impulse_frames_Ns"]) for r in rows], "o-", ms=3, lw=0.8, color=f"C{k}",
                    label=f"model {name}, rotation {rotation}, to the frame")
            ax.plot(force, [float(r["impulse_Ns"]) for r in rows], ":", lw=0.8, color=f"C{k}")
            hz_text = "" if method == "continuous" else f"{hz:g}"
            theirs = [(float(r["force_N"]), float(r["impulse_Ns"])) for r in thesis
                      if int(r["case"]) == case and r["method"] == ("continuous" if method == "continuous" else "pulsed")
                      and r["pulse_hz"] == hz_text and _number(r["impulse_Ns"]) is not None]
            if theirs:
                ax.plot(*zip(*sorted(theirs)), "x--", ms=4, lw=0.6, color=f"C{k}", label=f"thesis {name}")
        ax.set_xlabel("peak pull force (N)")
        ax.set_ylabel("impulse to dislodge (N s); dotted: to the event")
        ax.set_title(f"case {case}: impulse against the peak force, ours and the thesis'")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6)
        fig.tight_layout()
        path = out / f"case{case}_impulse_vs_force_N.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def report(study) -> list[Path]:
    """results/NAME/results.csv (one row per pull; replaces the runner's per-case export, which
    stays in results.sqlite), thresholds.csv, thesis_frames.csv (the pulls at the thesis'
    magnitudes against its table, `thesis_frames`) and the plots; returns the plot paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pulls, thresholds = gather(study)
    out = study.results
    for name, rows, columns in (("results.csv", pulls, pull_columns()), ("thresholds.csv", thresholds, THRESHOLD_COLUMNS)):
        with open(out / name, "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=columns, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    # the thesis' table as copied into the repository for the tests (plots only; skipped if absent)
    thesis_path = ROOT / "tests" / "data" / "dislodging_thesis.csv"
    thesis = read_csv(thesis_path, comments=True) if thesis_path.exists() else []
    frames = thesis_frames(pulls, thesis)
    if frames:
        with open(out / "thesis_frames.csv", "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=FRAME_COLUMNS, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(frames)
        agree = sum(bool(r["within_one_frame"]) for r in frames)
        print(f"thesis frames: {agree} of {len(frames)} rows within one frame (thesis_frames.csv)")
    paths = []
    for case in sorted({int(r["case"]) for r in pulls}):
        reference = THESIS_THRESHOLDS[(case, "continuous", 0.0)][1]
        for quantity, label in (("impulse_Ns", "impulse to dislodge (N s)"), ("dislodge_time_s", "time to dislodge (s)")):
            fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
            mine = [r for r in pulls if int(r["case"]) == case and r["dislodged"] == "True"]
            key = lambda r: (r["method"], _number(r["pulse_hz"]) or 0.0, float(r["thickness_mm"]), r.get("rotation") or "free")
            for k, series in enumerate(sorted({key(r) for r in mine})):
                colour = f"C{k}"
                rows = [r for r in mine if key(r) == series]
                rows.sort(key=lambda r: float(r["force_N"]))
                name = ("continuous" if series[0] == "continuous" else f"{series[1]:g} Hz") + \
                    (f", {series[2]:g} mm" if series[2] != 1.0 else "") + (", rotation held" if series[3] == "held" else "")
                x = [float(r["force_over_pullout"]) for r in rows]
                frames = "impulse_frames_Ns" if quantity == "impulse_Ns" else None
                axes[0].plot(x, [float(r[quantity]) for r in rows], "o-", ms=3, lw=0.6, color=colour, label=f"model {name}")
                axes[1].plot(x, [float(r[frames]) if frames else math.ceil(float(r[quantity]) / 0.005 - 1e-9) * 0.005
                                 for r in rows], "o-", ms=3, lw=0.6, color=colour, label=f"model {name}")
                if thesis and series[2] == 1.0:
                    method = "continuous" if series[0] == "continuous" else "pulsed"
                    hz = "" if series[0] == "continuous" else f"{series[1]:g}"
                    trows = [r for r in thesis if int(r["case"]) == case and r["method"] == method
                             and r["pulse_hz"] == hz and r["dislodge_frame"]]
                    value = (lambda r: _number(r["impulse_Ns"])) if frames else (lambda r: int(r["dislodge_frame"]) * 0.005)
                    points = [(float(r["force_N"]) / reference, value(r)) for r in trows if value(r) is not None]
                    if points:
                        axes[1].plot(*zip(*points), "x--", ms=4, lw=0.6, color=colour, label=f"thesis {name}")
            axes[0].set_title(f"case {case}: exact (event located inside the increment)")
            axes[1].set_title(f"case {case}: quantised to 0.005 s frames; thesis x = F / {reference:g} N")
            for ax in axes:  # near the threshold; pulls at the thesis' absolute magnitudes are in results.csv
                ax.set_xlabel("peak pull force / quasi-static pull-out force")
                ax.set_xlim(0.995, 1.16)
                ax.grid(True, alpha=0.3)
                ax.set_yscale("log")
            axes[0].set_ylabel(label)
            axes[0].legend(fontsize=6, ncol=2)
            axes[1].legend(fontsize=6, ncol=2)
            fig.tight_layout()
            path = out / f"case{case}_{quantity.split('_')[0]}_vs_force.png"
            fig.savefig(path, dpi=110)
            plt.close(fig)
            paths.append(path)
    paths += absolute_impulse_plots(pulls, thesis, out)
    paths += render_snapshots(study)
    if thresholds:
        fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
        for case, rotation in sorted({(r["case"], r["rotation"]) for r in thresholds}):
            mine = [r for r in thresholds if r["case"] == case and r["rotation"] == rotation and r["thickness_mm"] == 1.0]
            rows = sorted((r for r in mine if r["method"] == "pulse"), key=lambda r: float(r["pulse_hz"]))
            hz = [float(r["pulse_hz"]) for r in rows]
            continuous = [r for r in mine if r["method"] == "continuous"]
            label = f"case {case}" + (", rotation held" if rotation == "held" else "")
            axes[0].plot(hz, [r["threshold_force_N"] for r in rows], "o-", label=f"model {label}")
            axes[0].plot(hz, [r["thesis_threshold_N"] or np.nan for r in rows], "x--", label=f"thesis case {case}")
            if continuous:
                axes[0].axhline(continuous[0]["threshold_force_N"], ls=":", color="k", lw=0.8)
            axes[1].plot(hz, [r["threshold_over_pullout"] or np.nan for r in rows], "o-",
                         label=f"model {label} / quasi-static pull-out")
            axes[1].plot(hz, [r["thesis_over_thesis_continuous"] or np.nan for r in rows], "x--",
                         label=f"thesis case {case} / its continuous threshold")
        axes[0].set_ylabel("threshold peak force (N)")
        axes[1].set_ylabel("normalised threshold")
        for ax in axes:
            ax.set_xlabel("pulse frequency (Hz)")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        path = out / "threshold_vs_frequency.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths
