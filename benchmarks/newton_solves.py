"""Where a run's solve time goes: every Newton solve of a scene, by how it ended.

Runs a scene in this process and reads its result's `info["newton_solves"]`: each
`SchurNewton.solve` counted with its Newton iterations and wall time in three kinds, plain solves
(no stabilisation spring on), the continuation's converged solves (the stabilised and the
pseudo-transient continuation, a spring on) and the solves that failed (any kind; the stepper then
tries the next way or cuts the increment). With `--slow` it does so for each slow converged case
of the last `make stability` sweep (results/stability/stability.toml: the cases whose solve time
exceeds 3x their neighbours') and writes results/stability/newton_solves.md.

    python -m benchmarks.newton_solves scenes/wedging_2d.toml [--set KEY=VALUE ...]
    python -m benchmarks.newton_solves --slow
"""
import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import femcontact
from benchmarks.stability import OUT, read_results, slow_cases
from femcontact.config.scene import read_toml
from femcontact.outputs.tables import markdown_table
from femcontact.solver.newton import SOLVE_KINDS as KINDS


def run_recorded(scene: dict) -> tuple[dict, object]:
    """Run the resolved scene (in a scratch directory): ({kind: (solves, Newton iterations, s)}, Result)."""
    with tempfile.TemporaryDirectory() as out:
        result = femcontact.run(scene, out=out, quiet=True)
    solves = result.info["newton_solves"]
    return {kind: (solves[kind]["solves"], solves[kind]["iterations"], solves[kind]["seconds"]) for kind in KINDS}, result


ROW_COLUMNS = ["case", "status", "solve (s)"] + [f"{kind}: solves / iterations / s" for kind in KINDS]


def row(name: str, totals: dict, result) -> list:
    return [name, result.status, result.timings.get("solve", 0.0)] + [
        f"{n} / {its} / {seconds:.1f}" for n, its, seconds in (totals[kind] for kind in KINDS)]


def slow_report() -> str:
    """The breakdown of the last sweep's slow 2-D cases, each run again, and their sums."""
    study = read_toml(OUT / "stability.toml")
    results = read_results("stability", study["sweep"]["cases"], Path(study["study"]["scene"]))
    table, sums = [], {kind: np.zeros(3) for kind in KINDS}
    for cid, _, _ in slow_cases(results):
        scene = results[cid][0]
        totals, result = run_recorded(scene)
        print(f"{cid}: " + ", ".join(f"{kind} {n} solves {its} iterations {s:.1f} s"
                                     for kind, (n, its, s) in totals.items()), flush=True)
        table.append(row(cid, totals, result))
        for kind in KINDS:
            sums[kind] += totals[kind]
    seconds = sum(total[2] for total in sums.values()) or 1.0
    lines = ["# Where the slow cases' solve time goes", "",
             "`python -m benchmarks.newton_solves --slow`: the slow converged 2-D cases of the last "
             "`make stability` sweep, each run again with its Newton solves recorded.", "",
             *markdown_table(ROW_COLUMNS, table, formats=[None, None, "{:.1f}", None, None, None]), "",
             f"All {len(table)} cases: " + "; ".join(
                 f"{kind} {int(n)} solves, {int(its)} Newton iterations, {s:.1f} s ({100 * s / seconds:.0f} %)"
                 for kind, (n, its, s) in sums.items()), ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.newton_solves", description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", help="a scene file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scene override")
    parser.add_argument("--slow", action="store_true", help="the slow cases of the last `make stability` sweep")
    args = parser.parse_args(argv)
    if args.slow == bool(args.scene):
        parser.error("give a scene file or --slow")
    if args.slow:
        text = slow_report()
        (OUT / "newton_solves.md").write_text(text)
        print(text)
        print(f"written: {OUT / 'newton_solves.md'}")
        return 0
    totals, result = run_recorded(femcontact.load_scene(args.scene, args.set))
    print(json.dumps({"status": result.status, "solve_s": result.timings.get("solve"),
                      **{kind: dict(zip(("solves", "iterations", "seconds"), values)) for kind, values in totals.items()}}))
    return 0


if __name__ == "__main__":
    from femcontact.process import quiet_logging

    quiet_logging()
    sys.exit(main())
