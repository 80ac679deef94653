"""results/plasticity_wedging/ from the wedge map run elastic (studies/wedging.toml) and with
`plasticity` (studies/wedging_plastic.toml, the same cases on stainless 316): per map point,
wedged or not in each, whether the elastic peak passes the yield stress, whether the plastic run
yields (PEEQ > 0), its peak PEEQ and plastic zone after release, and the change of the residual
force that holds the peg (docs/plasticity.md). Writes plasticity_wedging.md, .csv and .png.

The family's `Gathering` "plasticity_wedging": `python -m femcontact.study.gathering
plasticity_wedging [--results results]` (`make plasticity_wedging` runs both studies first).
A map point is the case's scene without `effects` and `plasticity`: the two studies' cases pair
by it, whatever order or subset of cases each file makes.
"""
import csv
import json
import math
from pathlib import Path

from femcontact.families.repository import STUDIES
from femcontact.io import write_atomic, write_text_atomic
from femcontact.outputs.tables import markdown_table

ELASTIC, PLASTIC = "wedging", "wedging_plastic"
"""The studies gathered (studies/NAME.toml): the map elastic, and with `plasticity`."""
STUDY_FILES = (STUDIES / f"{ELASTIC}.toml", STUDIES / f"{PLASTIC}.toml")
LAW_KEYS = ("effects", "plasticity")
"""Scene keys in which the two runs of one map point differ."""
LABELLED_CHANGE = 0.005
"""A residual force change (fraction) the plot names its point at."""
PEEQ_FLOOR = 1e-6
"""The smallest PEEQ the plot's colour scale shows; below it (and at 0) a point is drawn hollow."""
COLUMNS = ["l_d_mm", "D_mm", "d_mm", "mu", "load", "mesh_resolution", "depth_over_l_crit", "depth_over_l_max",
           "wedged_elastic", "wedged_plastic", "peak_von_mises_elastic_MPa", "elastic_over_yield", "yielded_plastic",
           "max_peeq", "plastic_zone", "peak_von_mises_plastic_MPa", "R_A_elastic_N", "R_A_plastic_N", "R_A_change"]
"""The columns of plasticity_wedging.csv (R_A_change: a fraction, empty where the elastic run is not wedged)."""


def map_point(scene: dict) -> str:
    """The scene without the keys of its material law: equal for the elastic and the plastic run of a point."""
    return json.dumps({key: value for key, value in scene.items() if key not in LAW_KEYS}, sort_keys=True)


def load_text(scene: dict) -> str:
    """The first step's load as a table shows it: 'F (-5, 1) N' or 'M 200 N*mm'."""
    step = scene["steps"][0]
    if step["moment"]:
        return "M " + ", ".join(f"{m:g}" for m in step["moment"]) + " N*mm"
    return "F (" + ", ".join(f"{f:g}" for f in step["force"]) + ") N"


def point_row(scene: dict, elastic: dict, plastic: dict) -> dict:
    """One map point's row from the metrics of its elastic and its plastic run (COLUMNS)."""
    release = scene["steps"][-1]["name"]
    peeq, zone = plastic[f"{release}.max_peeq"], plastic[f"{release}.plastic_zone"]
    R_e, R_p = elastic["residual_force_A"], plastic["residual_force_A"]
    return {"l_d_mm": scene["peg"]["insertion_depth"], "D_mm": scene["hole"]["width"], "d_mm": scene["peg"]["width"],
            "mu": scene["contact"]["mu"], "load": load_text(scene), "load_scale_N": elastic["load_scale"],
            "mesh_resolution": scene["mesh"]["resolution"],
            "depth_over_l_crit": elastic["depth_over_l_crit"], "depth_over_l_max": elastic["depth_over_l_max"],
            "wedged_elastic": elastic["wedged"], "wedged_plastic": plastic["wedged"],
            "peak_von_mises_elastic_MPa": elastic["max_von_mises"], "elastic_over_yield": elastic["yield_ratio"],
            "yielded_plastic": peeq > 0, "max_peeq": peeq, "plastic_zone": zone,
            "peak_von_mises_plastic_MPa": plastic["max_von_mises"], "R_A_elastic_N": R_e, "R_A_plastic_N": R_p,
            "R_A_change": R_p / R_e - 1 if elastic["wedged"] else None}


def pair(cases: dict) -> tuple[list[dict], list[dict]]:
    """(rows of the map points with an ok elastic and plastic run, in the elastic study's order;
    the scenes of the points only one of them has)."""
    plastic = {map_point(case.scene): metrics for case, metrics in cases.get(PLASTIC, [])}
    rows, alone = [], []
    for case, metrics in cases.get(ELASTIC, []):
        partner = plastic.pop(map_point(case.scene), None)
        if partner is None:
            alone.append(case.scene)
        else:
            rows.append(point_row(case.scene, metrics, partner))
    return rows, alone + [json.loads(point) for point in plastic]


def findings(rows: list[dict]) -> list[str]:
    """The map's answer in a few measured sentences."""
    if not rows:
        return ["No map point has both an elastic and a plastic result yet."]
    above = [r for r in rows if r["elastic_over_yield"] > 1]
    yielded = [r for r in rows if r["yielded_plastic"]]
    flipped = [r for r in rows if r["wedged_elastic"] != r["wedged_plastic"]]
    changes = [r["R_A_change"] for r in rows if r["R_A_change"] is not None]
    worst = max(rows, key=lambda r: r["max_peeq"])
    lines = [f"- {len(rows)} map points; the elastic peak von Mises stress passes the yield stress at {len(above)}, "
             f"the plastic run yields (PEEQ > 0) at {len(yielded)}"
             + (" (the same points)." if above == yielded else "."),
             f"- Wedged or not: the plastic run answers as the elastic one at {len(rows) - len(flipped)} of "
             f"{len(rows)} points" + (": " + "; ".join(f"l_d {r['l_d_mm']:g}, D {r['D_mm']:g}, mu {r['mu']:g}, "
                                                          f"{r['load']}" for r in flipped) if flipped else "") + "."]
    if changes:
        lines.append(f"- Residual force R_A of the points wedged elastically, plastic / elastic - 1: from "
                     f"{100 * min(changes):+.2f} % to {100 * max(changes):+.2f} %.")
    if yielded:
        lines.append(f"- Largest PEEQ after release {worst['max_peeq']:.2e} in a plastic zone of "
                     f"{worst['plastic_zone']:.2e} mm^2, at l_d {worst['l_d_mm']:g}, D {worst['D_mm']:g}, "
                     f"mu {worst['mu']:g}, {worst['load']}.")
    return lines


def page(rows: list[dict], alone: list[dict]) -> str:
    table = markdown_table(
        ["l_d (mm)", "D (mm)", "mu", "load", "l_d / l_crit", "l_d / mu d", "wedged elastic / plastic",
         "elastic peak von Mises / yield", "yielded (PEEQ > 0)", "max PEEQ", "plastic zone (mm^2)",
         "R_A elastic (N)", "R_A plastic (N)", "R_A change"],
        [[r["l_d_mm"], r["D_mm"], r["mu"], r["load"], r["depth_over_l_crit"], r["depth_over_l_max"],
          f"{'yes' if r['wedged_elastic'] else 'no'} / {'yes' if r['wedged_plastic'] else 'no'}",
          r["elastic_over_yield"], r["yielded_plastic"], r["max_peeq"], r["plastic_zone"], r["R_A_elastic_N"],
          r["R_A_plastic_N"], "-" if r["R_A_change"] is None else f"{100 * r['R_A_change']:+.2f} %"] for r in rows],
        formats=["{:g}", "{:g}", "{:g}", None, "{:.2f}", "{:.2f}", None, "{:.2f}", None, "{:.2e}", "{:.2e}",
                 "{:.3f}", "{:.3f}", None])
    lines = ["# The wedge map with plasticity (stainless 316)", "",
             "`make plasticity_wedging`: the cases of studies/wedging.toml, elastic and with `plasticity` "
             "(studies/wedging_plastic.toml: 210 MPa, 290 MPa at plastic strain 1), paired by map point"
             + "".join(f", mesh resolution {value:g}" for value in sorted({r["mesh_resolution"] for r in rows})) + ". "
             "PEEQ and plastic zone after release; R_A is the residual force on block A that holds the "
             "released peg; the change is given where the elastic run is wedged. See docs/plasticity.md.", "",
             "## Findings", "", *findings(rows), "", "## Per map point", "", *table]
    if alone:
        lines += ["", f"{len(alone)} map point(s) with only one of the two results (not run yet, failed, or "
                  "without static equilibrium under load): "
                  + "; ".join(f"l_d {s['peg']['insertion_depth']:g}, D {s['hole']['width']:g}, "
                              f"mu {s['contact']['mu']:g}, {load_text(s)}" for s in alone)]
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], path: Path) -> None:
    """Left: the normalised wedge map, each point coloured by its PEEQ after release (hollow: no
    plastic strain), a circle when the plastic run is wedged, a cross when not, larger for a larger
    load. Right: the residual force change against the elastic peak stress over the yield stress."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import FuncFormatter

    peeqs = [r["max_peeq"] for r in rows if r["max_peeq"] >= PEEQ_FLOOR]
    norm = LogNorm(PEEQ_FLOOR, max(peeqs + [10 * PEEQ_FLOOR]))
    colours = plt.get_cmap("plasma_r")
    figure, (left, right) = plt.subplots(1, 2, figsize=(13, 5), layout="constrained")
    largest = max((r["load_scale_N"] for r in rows), default=1.0)
    for r in sorted(rows, key=lambda r: -r["load_scale_N"]):  # the smaller loads drawn on top
        size = 40 + 160 * math.sqrt(r["load_scale_N"] / largest)
        plastic = r["max_peeq"] >= PEEQ_FLOOR
        colour = colours(norm(r["max_peeq"])) if plastic else "none"
        if r["wedged_plastic"]:
            left.scatter(r["depth_over_l_crit"], r["depth_over_l_max"], s=size, marker="o", facecolors=colour,
                         edgecolors="k", linewidths=0.8, zorder=3)
        else:
            left.scatter(r["depth_over_l_crit"], r["depth_over_l_max"], s=size, marker="x",
                         color=colour if plastic else "grey", linewidths=2, zorder=3)
        if r["R_A_change"] is not None:
            right.scatter(r["elastic_over_yield"], 100 * r["R_A_change"], s=size, marker="o", facecolors=colour,
                          edgecolors="k", linewidths=0.8, zorder=3)
    for r in rows:
        if r["R_A_change"] is not None and abs(r["R_A_change"]) >= LABELLED_CHANGE:
            right.annotate(f"l_d {r['l_d_mm']:g}, D {r['D_mm']:g}, mu {r['mu']:g}, {r['load']}",
                           (r["elastic_over_yield"], 100 * r["R_A_change"]), xytext=(-8, 4),
                           textcoords="offset points", ha="right", fontsize=7)
    left.axvline(1.0, color="k", linestyle="--", lw=0.8, label="l_d = l_crit")
    left.axhline(1.0, color="k", linestyle=":", lw=0.8, label="l_d = mu d")
    for marker, face, label in (("o", "tab:purple", "wedged (plastic run), PEEQ > 0"),
                                ("o", "none", "wedged, no plastic strain"), ("x", "grey", "not wedged")):
        left.scatter([], [], marker=marker, s=60, label=label,
                     **({"color": face} if marker == "x" else {"facecolors": face, "edgecolors": "k"}))
    left.set(xscale="log", xlabel="l_d / l_crit", ylabel="l_d / mu d",
             title="Wedge map on stainless 316 with plasticity\n(marker size: load; colour: PEEQ after release)")
    left.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    left.xaxis.set_minor_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    left.legend(fontsize=7, loc="upper left")
    right.axvline(1.0, color="grey", lw=0.8, ls=":")
    right.axhline(0.0, color="grey", lw=0.8)
    right.set(xlabel="elastic run: peak von Mises / yield stress",
              ylabel="R_A plastic / elastic - 1 (%)",
              title="Residual force that holds the peg, plastic against elastic\n(points wedged elastically)")
    for axes in (left, right):
        axes.grid(True, alpha=0.3)
    figure.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=colours), ax=right, label="max PEEQ after release")
    write_atomic(path, lambda stream: figure.savefig(stream, format="png", dpi=110), binary=True)
    plt.close(figure)


def write(cases: dict, out: Path) -> None:
    """plasticity_wedging.md, .csv and .png in `out` from the ok cases of the two studies."""
    rows, alone = pair(cases)
    write_text_atomic(out / "plasticity_wedging.md", page(rows, alone))

    def table(stream):
        writer = csv.DictWriter(stream, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)

    write_atomic(out / "plasticity_wedging.csv", table)
    plot(rows, out / "plasticity_wedging.png")
