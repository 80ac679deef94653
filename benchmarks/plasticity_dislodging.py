"""`make plasticity_dislodging`: can the wedged peg be pulled free without damaging the hole?

The thesis' dislodging case 1 (scenes/dislodging_2d.toml: moment-wedged peg d 50 in D 50.05,
l_d 7, mu 0.2) with `plasticity` on the thesis' stainless 316 (210 MPa, 290 MPa at plastic
strain 1), pulled at the peg top by a constant force and by 50 Hz triangle pulses, each pull
from the wedged state. Per method: the least pull that frees the peg (`Puller.threshold`) and
the least pull that adds more than `dislodging.peeq_limit` (1e-4) of plastic strain to the
wedged state's (`Puller.damage_threshold`), by the same bisection; the window between them is
the range of pulls that free the peg without damage. A few pulls across 0.25-1.5 times the
quasi-static pull-out show the plastic strain each adds.

Writes results/plasticity_dislodging/NAME.md, .json and .png (NAME: resolution_R, or --name).

    python -m benchmarks.plasticity_dislodging [--resolution 0.5] [--set KEY=VALUE ...] [--name NAME]
"""
import argparse
import json
import time
from pathlib import Path

from femcontact.families import load_scene
from femcontact.families.dislodging.pull import Puller
from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table

OUT = Path("results/plasticity_dislodging")
SCENE = SCENES / "dislodging_2d.toml"
PLASTIC = ["effects=['friction', 'plane_strain', 'inertia', 'plasticity']", "plasticity.hardening=[[0, 210], [1, 290]]",
           "dislodging.forces=[]"]
METHODS = (("continuous", 0.0), ("pulse", 50.0))
SAMPLES = (0.25, 0.5, 0.75, 1.25, 1.5)
"""Pulls run for the plot besides the searches, in multiples of the quasi-static pull-out."""


def plastic_puller(overrides: list[str] = ()) -> Puller:
    """The wedged peg of the thesis' case 1 on stainless 316 (its rotation free, as the scene)."""
    return Puller(load_scene(SCENE, PLASTIC + list(overrides)), held_pullout=False)


def window(puller: Puller, method: str, frequency: float, samples=SAMPLES) -> dict:
    """The least freeing and the least damaging pull of one method, and the pulls run."""
    pulls = [puller.pull(f * puller.pullout_force, method, frequency) for f in samples]
    found = puller.damage_window(method, frequency, pulls)
    return {"method": method, "pulse_hz": frequency, **found,
            "pulls": [{k: row[k] for k in ("force_N", "dislodged", "peeq_added", "damaging", "wall_s")}
                      for row in sorted(pulls, key=lambda r: r["force_N"])]}


def name(method: dict) -> str:
    """'continuous' or 'pulse 50 Hz'."""
    return method["method"] + (f" {method['pulse_hz']:g} Hz" if method["pulse_hz"] else "")


def page(result: dict, seconds: float) -> str:
    r = result
    lines = ["# Dislodging on stainless 316: is there a pull that frees the peg without damage?", "",
             f"`{r['command']}`, {seconds:.0f} s on one core. See docs/plasticity.md.", "",
             f"Mesh resolution {r['resolution']:g} ({r['dofs']} dofs). Wedged state: max PEEQ {r['wedged_max_peeq']:.2e}, "
             f"plastic zone {r['wedged_plastic_zone']:.2e} mm^2, quasi-static pull-out {r['pullout_N']:.3f} N. "
             f"Damage: a pull adds more than {r['peeq_limit']:g} of PEEQ to the wedged state's.", "",
             *markdown_table(["pull", "least freeing (N)", "least damaging (N)", "window (N)", "bracket (N)"],
                             [[name(m), m["threshold_force_N"],
                               f"none up to {m['no_damage_up_to_N']:.3f}" if m["damage_threshold_N"] is None
                               else f"{m['damage_threshold_N']:.3f}",
                               "> {:+.3f}".format(m["no_damage_up_to_N"] - m["threshold_force_N"])
                               if m["damage_window_N"] is None else f"{m['damage_window_N']:+.3f}", m["bracket_N"]]
                              for m in r["methods"]], formats=[None, "{:.3f}", None, None, "{:.3f}"]), "",
             "## Every pull", ""]
    for m in r["methods"]:
        lines += [f"{name(m)}:", "",
                  *markdown_table(["force (N)", "/ pull-out", "freed", "PEEQ added", "wall (s)"],
                                  [[p["force_N"], p["force_N"] / r["pullout_N"], p["dislodged"], p["peeq_added"],
                                    p["wall_s"]] for p in m["pulls"]],
                                  formats=["{:.3f}", "{:.3f}", None, "{:.2e}", "{:.1f}"]), ""]
    return "\n".join(lines)


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = result["methods"]
    fig, axes = plt.subplots(1, len(methods), figsize=(5.5 * len(methods), 4.2), sharey=True)
    pullout, limit = result["pullout_N"], result["peeq_limit"]
    for axis, m in zip(axes, methods):
        for freed, marker, label in ((True, "o", "peg freed"), (False, "x", "peg held")):
            pulls = [p for p in m["pulls"] if p["dislodged"] == freed]
            axis.semilogy([p["force_N"] / pullout for p in pulls], [max(p["peeq_added"], 1e-7) for p in pulls],
                          marker, color="tab:blue" if freed else "tab:grey", label=label)
        axis.axhline(limit, color="tab:red", ls="--", lw=1, label=f"PEEQ limit {limit:g}")
        free = m["threshold_force_N"] / pullout
        axis.axvline(free, color="tab:green", lw=1.5, label=f"least freeing pull {m['threshold_force_N']:.2f} N")
        if m["damage_threshold_N"] is None:
            damage = m["no_damage_up_to_N"] / pullout
            verdict = f"window > {m['no_damage_up_to_N'] - m['threshold_force_N']:.1f} N"
        else:
            damage = m["damage_threshold_N"] / pullout
            axis.axvline(damage, color="tab:red", lw=1.5, label=f"least damaging pull {m['damage_threshold_N']:.2f} N")
            verdict = (f"window {m['damage_window_N']:.2f} N" if damage > free
                       else f"no window: damage starts {-m['damage_window_N']:.2f} N below")
        if damage > free:
            axis.axvspan(free, damage, color="tab:green", alpha=0.15, label="frees without damage")
        axis.set(xlabel="peak pull / quasi-static pull-out", title=f"{name(m)}: {verdict}")
        axis.legend(fontsize=7, loc="lower right")
    axes[0].set_ylabel("PEEQ added by the pull")
    fig.suptitle(f"Thesis case 1 on stainless 316, mesh resolution {result['resolution']:g}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=float, default=0.5, help="mesh.resolution of the blocks")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scene override")
    parser.add_argument("--name", help="file name of the results (default resolution_R)")
    args = parser.parse_args()
    resolution = args.resolution
    start = time.perf_counter()
    OUT.mkdir(parents=True, exist_ok=True)
    puller = plastic_puller([f"mesh.resolution={resolution}"] + args.set)
    command = " ".join(["python -m benchmarks.plasticity_dislodging", f"--resolution {resolution:g}",
                        *(f"--set '{o}'" for o in args.set), *([f"--name {args.name}"] if args.name else [])])
    result = {"command": command, "overrides": args.set, "resolution": resolution, "dofs": puller.simulation.dofs, "pullout_N": puller.pullout_force,
              "peeq_limit": puller.settings["peeq_limit"], "wedged_max_peeq": puller.wedged_row["max_peeq"],
              "wedged_plastic_zone": puller.wedged_row["plastic_zone"], "methods": []}
    for method, frequency in METHODS:
        result["methods"].append(window(puller, method, frequency))
        print({k: v for k, v in result["methods"][-1].items() if k != "pulls"}, flush=True)
    seconds = time.perf_counter() - start
    name = args.name or f"resolution_{resolution:g}"
    (OUT / f"{name}.json").write_text(json.dumps(result, indent=1))
    (OUT / f"{name}.md").write_text(page(result, seconds))
    plot(result, OUT / f"{name}.png")
    print(f"results in {OUT / name}.md and .png ({seconds:.0f} s)")


if __name__ == "__main__":
    from femcontact.process import quiet_logging

    quiet_logging()
    main()
