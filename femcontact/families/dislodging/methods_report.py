"""results/dislodging_methods/ from the studies dislodging_methods_2d and dislodging_methods_3d
and dislodging_methods_frequency (docs/dislodging_methods.md): degree_of_wedging.csv,
methods.csv (50 Hz), methods_frequency.csv (every frequency), optimum.json (least impulse, and
least peak force under "peak_force_optimum"), optimum.csv (every pull of the impulse
optimisation), optimum_peak.csv (every evaluation of the peak one), pullout_3d.csv, the plots
and summary.md with the ranking of the ways out by impulse and by peak force.

The family's `Gathering` "dislodging_methods": `python -m femcontact.study.gathering dislodging_methods
[--results results]` hands `write` the cases of the three study files.
"""
import csv
import json
from pathlib import Path

from femcontact.families.repository import STUDIES
from femcontact.io import read_csv
from femcontact.outputs.tables import markdown_table
from femcontact.references.richardson import range_error

STUDY_NAMES = ("dislodging_methods_2d", "dislodging_methods_3d", "dislodging_methods_frequency")
"""The studies gathered (studies/NAME.toml)."""
STUDY_FILES = tuple(STUDIES / f"{name}.toml" for name in STUDY_NAMES)
DEGREE_COLUMNS = ["peg.width", "hole.width", "clearance_mm", "peg.insertion_depth", "contact.mu", "wedging_moment_Nmm",
                  "wedged_N_A", "wedged_N_B", "wedged_T_A", "wedged_T_B", "tilt_deg", "pullout_force_N",
                  "degree_of_wedging", "degree_estimate", "pullout_rotation_held_N", "degree_of_wedging_rotation_held",
                  "one_dof_first_slip_N", "one_dof_full_slide_N"]
METHOD_COLUMNS = ["method", "base_pull", "pulse_hz", "threshold_force_N", "impulse_at_threshold_Ns", "threshold_over_pullout", "bracket_N",
                  "dislodge_time_at_threshold_s", "least_impulse_Ns", "least_impulse_peak_N", "quasi_static_pullout_N",
                  "pulls", "loads"]
LOADS = {"continuous": "constant vertical pull at the peg top",
         "pulse": "vertical triangle pulses",
         "shake": "lateral triangle pulses at the peg top, against the wedging moment",
         "twist": "moment triangle pulses, against the wedging moment; F = M / d (d = 50 mm)",
         "pull_shake": "constant vertical pull {base_pull:g} x pull-out + lateral triangle pulses; F = |(F_lat, F_pull)|"}
BASE_PULL = 0.5
"""The base pull (fraction of the pull-out) of the pull-plus-shake rows the frequency plot joins."""
PEAK_COLUMNS = ["shape", "pulse_hz", "duty", "threshold_force_N", "bracket_N", "impulse_at_threshold_Ns",
                "dislodge_time_at_threshold_s", "pulls"]


def _write_csv(path: Path, rows: list[dict], columns: list[str]) -> None:
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)


def degree_rows(cases) -> list[dict]:
    rows = []
    for case, m in cases:
        if case.scene["dislodging"]["task"] != "wedge":
            continue
        sc = case.scene
        rows.append({"peg.width": sc["peg"]["width"], "hole.width": sc["hole"]["width"],
                     "clearance_mm": round(sc["hole"]["width"] - sc["peg"]["width"], 6),
                     "peg.insertion_depth": sc["peg"]["insertion_depth"], "contact.mu": sc["contact"]["mu"],
                     "wedging_moment_Nmm": sc["steps"][0]["moment"][0],
                     **{k: m[k] for k in ("wedged_N_A", "wedged_N_B", "wedged_T_A", "wedged_T_B", "tilt_deg",
                                          "degree_of_wedging", "degree_of_wedging_rotation_held",
                                          "one_dof_first_slip_N", "one_dof_full_slide_N")},
                     "pullout_force_N": m["quasi_static_pullout_N"],
                     "degree_estimate": 1 - sc["peg"]["insertion_depth"] / (sc["contact"]["mu"] * sc["peg"]["width"]),
                     "pullout_rotation_held_N": m["quasi_static_pullout_N_rotation_held"]})
    return rows


def method_rows(cases) -> tuple[list[dict], list[dict]]:
    """methods.csv rows and every pull of the bisections (with its method)."""
    rows, pulls = [], []
    for case, m in cases:
        s = case.scene["dislodging"]
        if s["task"] != "threshold" or "threshold_force_N" not in m:
            continue
        rows.append({"method": s["method"], "pulse_hz": s["pulse_hz"] if s["method"] != "continuous" else "",
                     "base_pull": s["base_pull"] if s["method"] == "pull_shake" else "",
                     "threshold_over_pullout": m["threshold_force_N"] / m["quasi_static_pullout_N"],
                     "loads": LOADS[s["method"]].format(base_pull=s["base_pull"]),
                     **{k: m.get(k, "") for k in METHOD_COLUMNS if k in m}})
        if (case.dir / "pulls.csv").exists():
            mine = read_csv(case.dir / "pulls.csv")
            if default_base_pull(rows[-1]):  # the plot's one line per method
                pulls += mine
            out = [r for r in mine if r["dislodged"] == "True"]
            least = min(out, key=lambda r: float(r["impulse_Ns"]))  # over the bisection's pulls that dislodged
            rows[-1].update(least_impulse_Ns=float(least["impulse_Ns"]), least_impulse_peak_N=float(least["peak_force_N"]))
    order = list(LOADS)
    return sorted(rows, key=lambda r: (float(r["pulse_hz"] or 0), order.index(r["method"]), r["base_pull"])), pulls


def default_base_pull(row: dict) -> bool:
    """Whether a methods.csv row is one the plots join per method: no base pull, or BASE_PULL's."""
    return row["base_pull"] in ("", BASE_PULL)


def name(row: dict) -> str:
    """A methods.csv row's method, with its base pull where it has one: 'pull_shake 0.25 P'."""
    return row["method"] + (f" {row['base_pull']:g} P" if row["base_pull"] != "" else "")


def optimum_of(cases) -> tuple[dict | None, list[dict]]:
    for case, m in cases:
        if case.scene["dislodging"]["task"] == "optimise" and (case.dir / "optimum.json").exists():
            return json.loads((case.dir / "optimum.json").read_text()), read_csv(case.dir / "pulls.csv")
    return None, []


def peak_optimum_of(cases) -> tuple[dict | None, list[dict]]:
    """The least threshold peak over the 'optimise_peak' cases (one per set of shapes), with its
    verification, and every evaluation of all of them."""
    found = [json.loads((case.dir / "optimum_peak.json").read_text()) for case, m in cases
             if case.scene["dislodging"]["task"] == "optimise_peak" and (case.dir / "optimum_peak.json").exists()]
    if not found:
        return None, []
    evaluations = [e for optimum in found for e in optimum.pop("all_evaluations")]
    return min(found, key=lambda o: o["objective_peak_force_N"]), evaluations


def rows_3d(cases, degrees) -> list[dict]:
    """The 3-D thresholds with their 2-D estimates: the 1-DOF first slip of the 3-D contact forces,
    and the 2-D twin's degree of wedging times mu (N_A + N_B) of the 3-D wedge."""
    twin = [r for r in degrees if r["peg.width"] == 40.0 and r["clearance_mm"] == 0.1]
    out = []
    for case, m in cases:
        if "threshold_force_N" not in m:
            continue
        mu = case.scene["contact"]["mu"]
        common = {"mesh.resolution": case.scene["mesh"]["resolution"],
                  **{k: m[k] for k in ("wedged_N_A", "wedged_N_B", "wedged_T_A", "wedged_T_B", "sum_normal_N", "tilt_deg",
                                       "wedge_time_s")}}
        row = {"method": "pull along the axis", "threshold_force_N": m["threshold_force_N"], "bracket_N": m["bracket_N"],
               "goes_at": m.get("goes_at_force_N"),
               "degree_of_wedging": m["degree_of_wedging"], "estimate_2d_one_dof_first_slip_N": m["one_dof_first_slip_N"],
               "solves": m["pull_solves"], "time_s": m["pull_time_s"], **common}
        if twin:
            row.update(degree_of_wedging_2d_twin=twin[0]["degree_of_wedging"],
                       estimate_2d_twin_degree_N=twin[0]["degree_of_wedging"] * mu * m["sum_normal_N"])
            row["threshold_over_2d_twin_estimate"] = m["threshold_force_N"] / row["estimate_2d_twin_degree_N"]
        out.append(row)
        for prefix, method in (("twist", "twist about the axis"), ("across", "twist across the axis")):
            if f"{prefix}_threshold_moment_Nmm" in m:
                out.append({"method": method, "threshold_moment_Nmm": m[f"{prefix}_threshold_moment_Nmm"],
                            "bracket_Nmm": m[f"{prefix}_bracket_Nmm"], "goes_at": m.get(f"{prefix}_goes_at_Nmm"),
                            "over_friction_torque": m[f"{prefix}_over_friction_torque"],
                            "over_wedging_moment": m.get(f"{prefix}_over_wedging_moment", ""),
                            "solves": m[f"{prefix}_solves"], "time_s": m[f"{prefix}_time_s"], **common})
    return out


def errors_3d(three: list[dict]) -> list[dict]:
    """Each 3-D threshold (and the pull's degree of wedging) on the three finest meshes, with the
    finest value's discretisation error: 3 x their spread (`range_error`; the meshes are not
    refined by one ratio, so there is no Richardson estimate)."""
    out = []
    for method in dict.fromkeys(r["method"] for r in three):
        rows = sorted((r for r in three if r["method"] == method), key=lambda r: r["mesh.resolution"])[-3:]
        for key in ("threshold_force_N", "threshold_moment_Nmm", "degree_of_wedging"):
            values = [r.get(key) for r in rows]
            if len(rows) < 3 or any(v in (None, "") for v in values):
                continue
            error = range_error(values)
            out.append({"method": method, "quantity": key,
                        "mesh.resolution": ", ".join(f"{r['mesh.resolution']:g}" for r in rows),
                        "values": ", ".join(f"{v:.4g}" for v in values), "finest": f"{values[-1]:.4g}",
                        "estimated_error": f"{error:.1%}" if error is not None else ""})
    return out


def plots(out: Path, degrees, methods, pulls, optimum, trials) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def save(fig, name: str) -> None:
        fig.tight_layout()
        paths.append(out / name)
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)

    paths = []
    if degrees:
        base = {"peg.width": 50.0, "clearance_mm": 0.05, "peg.insertion_depth": 7.0, "contact.mu": 0.2,
                "wedging_moment_Nmm": 1000.0}
        fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), sharey=True)
        for ax, key in zip(axes, ("peg.insertion_depth", "clearance_mm", "contact.mu", "wedging_moment_Nmm")):
            rows = sorted([r for r in degrees if all(r[k] == v for k, v in base.items() if k != key)], key=lambda r: r[key])
            ax.plot([r[key] for r in rows], [r["degree_of_wedging"] for r in rows], "o-", label="free peg")
            ax.plot([r[key] for r in rows], [r["degree_of_wedging_rotation_held"] for r in rows], "s--",
                    label="rotation held")
            ax.plot([r[key] for r in rows], [r["degree_estimate"] for r in rows], "k:", label="1 - l_d / (mu d)")
            ax.set_xlabel(key)
            ax.grid(True, alpha=0.3)
        axes[0].set_ylabel("pull-out / (mu (N_A + N_B))")
        axes[0].legend(fontsize=8)
        fig.suptitle("Degree of wedging (2-D, thesis case 1 base, one key changed at a time)")
        save(fig, "degree_of_wedging.png")
    if pulls:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for k, method in enumerate(LOADS):
            rows = sorted([r for r in pulls if r["method"] == method and r["dislodged"] == "True"],
                          key=lambda r: float(r["peak_force_N"]))
            if rows:
                ax.plot([float(r["peak_force_N"]) for r in rows], [float(r["impulse_Ns"]) for r in rows], "o-",
                        ms=3, color=f"C{k}", label=method)
        ax.set_xlabel("peak force (N; twist M / d)")
        ax.set_ylabel("impulse to dislodge (N s)")
        ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title("Impulse against peak force: the dislodging pulls of each bisection")
        save(fig, "impulse_vs_peak_force.png")
    if trials:
        import numpy as np

        grid = [r for r in trials if r["phase"] == "grid"]
        shapes = list(dict.fromkeys(r["shape"] for r in grid))
        fig, axes = plt.subplots(1, len(shapes), figsize=(5 * len(shapes), 4), squeeze=False)
        hz = sorted({float(r["pulse_hz"]) for r in grid})
        duty = sorted({float(r["duty"]) for r in grid})
        for ax, shape in zip(axes[0], shapes):
            table = np.full((len(duty), len(hz)), np.nan)
            for r in grid:
                if r["shape"] == shape:
                    table[duty.index(float(r["duty"])), hz.index(float(r["pulse_hz"]))] = float(r["objective_Ns"])
            image = ax.imshow(table, origin="lower", aspect="auto", cmap="viridis")
            ax.set_xticks(range(len(hz)), [f"{h:g}" for h in hz])
            ax.set_yticks(range(len(duty)), [f"{d:g}" for d in duty])
            for i in range(len(duty)):
                for j in range(len(hz)):
                    ax.text(j, i, f"{table[i, j]:.2e}", ha="center", va="center", fontsize=7, color="w")
            ax.set_xlabel("pulse frequency (Hz)")
            ax.set_ylabel("duty")
            ax.set_title(f"{shape}: impulse to dislodge (N s)")
            fig.colorbar(image, ax=ax)
            nm = [r for r in trials if r["phase"] == "nelder-mead" and r["shape"] == shape]
            ax.plot([np.interp(float(r["pulse_hz"]), hz, range(len(hz))) for r in nm],
                    [np.interp(float(r["duty"]), duty, range(len(duty))) for r in nm], "r.", ms=4)
        fig.suptitle(f"Objective over frequency and duty at the grid's peak force; red: Nelder-Mead pulls "
                     f"(their own peak force); optimum {optimum['shape']} {optimum['pulse_hz']:.3g} Hz, duty "
                     f"{optimum['duty']:.3g}, {optimum['peak_force_N']:.3g} N" if optimum else "", fontsize=9)
        save(fig, "objective_frequency_duty.png")
    return paths


def frequency_plot(out: Path, rows: list[dict], evaluations: list[dict]) -> list[Path]:
    """methods_frequency.png: threshold peak / pull-out and least impulse of each method against
    the pulse frequency (the constant pull as a horizontal line), and the peak-force
    optimiser's evaluations."""
    pulsed = [r for r in rows if r["pulse_hz"] != ""]
    if len({r["pulse_hz"] for r in pulsed}) < 2:
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for k, method in enumerate(LOADS):
        mine = sorted([r for r in rows if r["method"] == method and default_base_pull(r)],
                      key=lambda r: float(r["pulse_hz"] or 0))
        for ax, key in zip(axes, ("threshold_over_pullout", "least_impulse_Ns")):
            if method == "continuous" and mine:
                ax.axhline(float(mine[0][key]), color=f"C{k}", ls="--", label=method)
            elif mine:
                ax.plot([float(r["pulse_hz"]) for r in mine], [float(r[key]) for r in mine], "o-", color=f"C{k}",
                        label=method)
    if evaluations:
        pullout = float(rows[0]["quasi_static_pullout_N"])
        axes[0].plot([e["pulse_hz"] for e in evaluations], [e["threshold_force_N"] / pullout for e in evaluations],
                     "kx", label="peak optimiser (vertical pulses, any shape and duty)")
    axes[0].set_ylabel("threshold peak force / quasi-static pull-out")
    axes[1].set_ylabel("least impulse of the dislodging pulls (N s)")
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("pulse frequency (Hz)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Ways out against the pulse frequency (2-D, triangle pulses, coarse mesh)")
    fig.tight_layout()
    fig.savefig(out / "methods_frequency.png", dpi=110)
    plt.close(fig)
    return [out / "methods_frequency.png"]


def _rankings(methods: list[dict]) -> list[str]:
    lines = []
    for key, label in (("impulse_at_threshold_Ns", "impulse at the threshold"),
                       ("least_impulse_Ns", "least impulse of the bisection's dislodging pulls"),
                       ("threshold_force_N", "peak force (threshold)")):
        ranked = sorted([r for r in methods if r.get(key, "") != ""], key=lambda r: float(r[key]))
        lines += ["", f"Ranking by {label} (least first): " + ", ".join(f"{name(r)} ({float(r[key]):.4g})"
                                                                           for r in ranked)]
    return lines


def _table(rows: list[dict], columns: list[str]) -> list[str]:
    """A Markdown table of `columns` of dict rows (a missing value empty)."""
    return markdown_table(columns, [[r.get(c, "") for c in columns] for r in rows])


def write(cases: dict[str, list[tuple]], out: Path) -> None:
    """Every file of results/dislodging_methods/ into `out` from `cases`: {study name: [(case,
    metrics) of its cases that ended ok]}, for each of STUDY_NAMES."""
    cases_2d, cases_3d, cases_frequency = (cases[name] for name in STUDY_NAMES)
    degrees = degree_rows(cases_2d)
    methods, pulls = method_rows(cases_2d)
    by_frequency, _ = method_rows(cases_2d + cases_frequency)
    optimum, trials = optimum_of(cases_2d)
    peak, evaluations = peak_optimum_of(cases_frequency)
    three = rows_3d(cases_3d, degrees)
    _write_csv(out / "degree_of_wedging.csv", degrees, DEGREE_COLUMNS)
    _write_csv(out / "methods.csv", methods, METHOD_COLUMNS)
    _write_csv(out / "methods_frequency.csv", by_frequency, METHOD_COLUMNS)
    if optimum or peak:
        (out / "optimum.json").write_text(json.dumps({**(optimum or {}), "peak_force_optimum": peak}, indent=2) + "\n")
    if optimum:
        _write_csv(out / "optimum.csv", trials, list(trials[0]) if trials else [])
    if evaluations:
        _write_csv(out / "optimum_peak.csv", evaluations, PEAK_COLUMNS)
    if three:
        columns = list(dict.fromkeys(k for r in three for k in r))
        _write_csv(out / "pullout_3d.csv", three, columns)
    paths = plots(out, degrees, methods, pulls, optimum, trials) + frequency_plot(out, by_frequency, evaluations)
    lines = ["# Ways out of a wedge", "",
             "Generated by `python -m femcontact.study.gathering dislodging_methods`; "
             "see docs/dislodging_methods.md.", "",
             "## Degree of wedging (2-D)", ""]
    lines += _table(degrees, ["peg.width", "clearance_mm", "peg.insertion_depth", "contact.mu", "wedging_moment_Nmm",
                              "wedged_N_A", "wedged_N_B", "pullout_force_N", "degree_of_wedging",
                              "degree_estimate", "degree_of_wedging_rotation_held"])
    lines += ["", "## Ways out (2-D, thesis case 1, coarse)", ""]
    lines += _table(methods, METHOD_COLUMNS[:-1])
    lines += _rankings(methods)
    frequencies = sorted({r["pulse_hz"] for r in by_frequency if r["pulse_hz"] != ""} - {50.0})
    if frequencies:
        lines += ["", "## Ways out at other frequencies (2-D, triangle pulses)", ""]
        lines += _table(by_frequency, METHOD_COLUMNS[:-1])
        continuous = [r for r in by_frequency if r["method"] == "continuous"]
        for hz in frequencies:
            lines += ["", f"At {hz:g} Hz (with the constant pull):"]
            lines += _rankings(continuous + [r for r in by_frequency if r["pulse_hz"] == hz])
    if optimum:
        lines += ["", "## Optimal pulse (least impulse)", ""] + _table([optimum], list(optimum))
    if peak:
        lines += ["", "## Optimal pulse (least threshold peak force)", ""] + _table([peak], list(peak))
        lines += ["", "Every evaluation (a bisection each):", ""] + _table(evaluations, PEAK_COLUMNS)
    if three:
        lines += ["", "## 3-D (quasi-static, 2 ranks)", ""] + _table(three, [c for c in (
            "method", "mesh.resolution", "threshold_force_N", "threshold_moment_Nmm", "goes_at", "sum_normal_N",
            "degree_of_wedging",
            "estimate_2d_one_dof_first_slip_N", "estimate_2d_twin_degree_N", "threshold_over_2d_twin_estimate",
            "over_friction_torque", "over_wedging_moment") if any(c in r for r in three)])
        errors = errors_3d(three)
        if errors:
            lines += ["", "## 3-D thresholds: discretisation error", "",
                      "On the three finest meshes; the error of the finest is 3 x their spread (largest - "
                      "smallest) / finest, Eca and Hoekstra's uncertainty where meshes do not converge "
                      "monotonically.", ""] + _table(errors, list(errors[0]))
    lines += ["", "Plots: " + ", ".join(p.name for p in paths)]
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print(f"dislodging_methods: {len(degrees)} wedged states, {len(methods)} methods, "
          f"{len(by_frequency)} methods x frequencies, impulse optimum {'yes' if optimum else 'no'}, peak-force "
          f"optimum {'yes' if peak else 'no'}, {len(three)} 3-D rows -> {out}")
