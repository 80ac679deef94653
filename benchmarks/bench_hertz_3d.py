"""`make bench_hertz_3d` (and the end of `make bench`): the 3-D Hertz benchmark beside GetFEM.

A rigid sphere (R 50 mm, P 2000 N) on a block (E 200 GPa, nu 0.3), its quarter meshed with
symmetry planes, on the meshes h_c = a/(2^(L+1) + 0.5) (uniform on r <= 1.5 a, graded
outside), L = 0..LEVELS, the same mesh for every code (femcontact's gmsh builder). Each code
runs as a whole process per level: `femcontact hertz --dim 3 --ranks 2` (P1 and P2) cold (an
empty JIT cache: the forms compiled in the process) and then warm (the cache the cold run
filled: its forms compiled), and
benchmarks/getfem_hertz.py --dim 3 (GetFEM 5.4 P2, one process: it compiles nothing). a and p0
come from each code's nodal pressures by one metric (`hertz.surface_metrics`). States the time
to reach and stay within 1 % of a and of p0 as the ratio femcontact (2 ranks) / GetFEM, warm
and cold, all measured in this run, and the machine's load average beside it. Writes
results/bench/hertz_3d.md and hertz_3d.json.

    python -m benchmarks.bench_hertz_3d [--levels N]
"""
import argparse
import json
import os
import sys
import tempfile

from femcontact.outputs.tables import markdown_table
from femcontact.references.hertz import analytic_sphere, benchmark_radius_3d, BENCHMARK_3D
from femcontact.families.hertz import benchmark as hertz

from benchmarks.bench import GETFEM_DRIVER, OUT, _run, getfem_available, time_within

LEVELS = 3
"""Finest level run by default: L3 (h_c = a/16.5; P1 16k dofs, P2 113k), the first at which
femcontact P1 stays within 1 % of a."""
RANKS = 2
GOAL = 0.5
"""femcontact's time to reach and stay within 1 %, at most this fraction of GetFEM's."""


def codes() -> list[tuple[str, list[str]]]:
    """(name, command without --contact-size) of every code run; GetFEM when importable."""
    femcontact = [sys.executable, "-m", "femcontact", "hertz", "--dim", "3", "--ranks", str(RANKS), "--json"]
    out = [(f"femcontact P{degree}", femcontact + ["--degree", str(degree)]) for degree in (1, 2)]
    if not getfem_available():
        out.append(("GetFEM P2", [sys.executable, str(GETFEM_DRIVER), "--dim", "3", "--degree", "2", "--json"]))
    return out


def load_average() -> float:
    """The machine's 1-minute load average (other jobs inflate every wall time alike)."""
    return os.getloadavg()[0]


def row(code: str, level: int, result: dict, cold: dict | None) -> dict:
    """One code at one level: dofs, Newton iterations, errors of a and p0, wall times (s)."""
    a, p0 = analytic_sphere(*(BENCHMARK_3D[k] for k in ("P", "R", "E", "nu")))
    measured = hertz.surface_metrics(*zip(*result["surface"]))
    return {"code": code, "level": level, "a_over_h": 2 ** (level + 1) + 0.5, "dofs": result["dofs"],
            "newton_per_increment": result["newton_per_increment"],
            "error_a": measured["a"] / a - 1, "error_p0": measured["p0"] / p0 - 1,
            "wall_time": result["wall_time"], "cold_time": (cold or result)["wall_time"],
            "solve_time": result["timings"]["solve"], "load": load_average()}


def measure(levels: int = LEVELS) -> dict:
    """Every code at every level, each a whole process (femcontact warm and cold)."""
    skipped = getfem_available()
    if skipped:
        print(f"GetFEM column skipped: {skipped}")
    a = benchmark_radius_3d()
    runs = codes()
    for _, command in runs:  # fill the JIT cache and the file cache outside the measurements
        _run(command + ["--contact-size", repr(a / 2.5)])
    rows = []
    for level in range(levels + 1):
        h = repr(a / (2 ** (level + 1) + 0.5))
        for code, command in runs:
            cold = None
            if code.startswith("femcontact"):  # cold in an empty JIT cache, then warm in the cache it filled
                with tempfile.TemporaryDirectory() as cache:
                    cold = _run(command + ["--contact-size", h], env={"XDG_CACHE_HOME": cache})
                    result = _run(command + ["--contact-size", h], env={"XDG_CACHE_HOME": cache})
                if cold is None:
                    continue
            else:
                result = _run(command + ["--contact-size", h])
            if result is None:
                continue
            rows.append(row(code, level, result, cold))
            r = rows[-1]
            print(f"  {code} L{level}: {r['dofs']} dofs, Newton {r['newton_per_increment']}, "
                  f"a {100 * r['error_a']:+.3f} %, p0 {100 * r['error_p0']:+.3f} %, "
                  f"{r['wall_time']:.1f} s warm, {r['cold_time']:.1f} s cold, load {r['load']:.1f}", flush=True)
    return {"rows": rows, "getfem_skipped": skipped, "levels": levels}


def goals(measured: dict) -> list[list[str]]:
    """[goal, measured, ratio, holds] for a and p0, P1 and P2, warm and cold."""
    rows, levels = measured["rows"], measured["levels"]
    out = []
    for key, label in (("error_a", "a"), ("error_p0", "p0")):
        reference = None if measured["getfem_skipped"] else time_within(rows, "GetFEM P2", key)
        for code in ("femcontact P1", "femcontact P2"):
            ours = time_within(rows, code, key)
            for timing in ("wall_time", "cold_time"):
                state = "warm" if timing == "wall_time" else "cold"
                goal = (f"3-D Hertz: time to reach and stay within 1 % of {label}, {code} ({RANKS} ranks, {state}) "
                        f"<= {GOAL:g}x GetFEM P2's")
                if ours is None or reference is None:
                    missing = [f"{name} not within 1 % at L{levels}" for name, found in
                               ((code, ours), ("GetFEM P2", reference)) if found is None]
                    out.append([goal, "; ".join(missing) or "GetFEM skipped", "-", "no" if ours is None else "-"])
                    continue
                ratio = ours[timing] / reference["wall_time"]
                out.append([goal, f"{ours[timing]:.1f} s (L{ours['level']}) vs {reference['wall_time']:.1f} s "
                            f"(L{reference['level']})", f"{ratio / GOAL:.2f}", "yes" if ratio <= GOAL else "no"])
    return out


def markdown(measured: dict) -> str:
    rows = measured["rows"]
    loads = [r["load"] for r in rows] or [load_average()]
    lines = ["## 3-D Hertz: femcontact and GetFEM on the same meshes (whole processes)", "",
             f"femcontact on {RANKS} ranks, warm (forms in the JIT cache) and cold (empty cache); GetFEM P2 one "
             f"process. Load average during the runs {min(loads):.1f}-{max(loads):.1f} on this machine.", ""]
    if measured["getfem_skipped"]:
        lines += [f"GetFEM column skipped: {measured['getfem_skipped']}.", ""]
    lines += markdown_table(
        ["code", "L", "a/h_c", "dofs", "Newton per increment", "error a", "error p0", "warm (s)", "cold (s)", "solve (s)"],
        [[r["code"], r["level"], r["a_over_h"], r["dofs"], str(r["newton_per_increment"]), 100 * r["error_a"],
          100 * r["error_p0"], r["wall_time"], r["cold_time"], r["solve_time"]] for r in rows],
        formats=[None] * 5 + ["{:+.2f} %"] * 2 + ["{:.1f}"] * 3)
    lines += ["", *markdown_table(["goal", "measured", "ratio to goal", "holds"], goals(measured))]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, default=LEVELS, help=f"finest level L (default {LEVELS})")
    args = parser.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    measured = measure(args.levels)
    (OUT / "hertz_3d.json").write_text(json.dumps(measured, indent=1))
    text = markdown(measured)
    (OUT / "hertz_3d.md").write_text(text)
    print(text)
    print(f"written: {OUT / 'hertz_3d.md'}")


if __name__ == "__main__":
    main()
