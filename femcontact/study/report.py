"""`femcontact report STUDY.toml`: plots, stress snapshots and a Markdown summary of a study.

Everything goes to results/NAME/: the plots the study declares ([[plot]], PNG),
snapshots/CASE_ID.png for the cases [snapshots] selects, and summary.md (a table
of the cases). The database is rebuilt from the case directories first, so the
report shows exactly what is on disk.
"""
import json
import math
import re
import sys
from pathlib import Path

from femcontact.errors import InputError
from femcontact.study.runner import flatten, get_key, load_study


def add_arguments(parser):
    parser.add_argument("study", help="study file (TOML)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="the same base-scene overrides given to `femcontact study`")
    parser.add_argument("--results", default="results", help="results root (default: results)")


def command(args) -> int:
    from femcontact.study.database import Database

    study = load_study(args.study, args.set, args.results)
    study.results.mkdir(parents=True, exist_ok=True)
    database = Database(study.database, study.keys)
    database.rebuild(study.cases)
    csv = database.export_csv(study.results / "results.csv")
    rows = database.rows()
    for row in rows:
        row["scene"] = json.loads(row["scene"]) if row["scene"] else {}
    plots = [write_plot(spec, rows, study.results) for spec in study.plots]
    snapshots = write_snapshots(study, {row["case_id"]: row for row in rows})
    summary = write_summary(study, database.csv_columns(), rows, plots, snapshots)
    print(f"study {study.settings['name']}: {len(rows)} of {len(study.cases)} cases have results")
    print(f"  table:     {summary}\n  data:      {csv} and {study.database}")
    for path in plots:
        print(f"  plot:      {path}")
    for path in snapshots:
        print(f"  snapshot:  {path}")
    return 0


def column(row: dict, name: str):
    """A row's value for a column, a metric name or any scene key; lists stored as JSON are decoded."""
    for key in (name, f"metric.{name}"):
        if key in row:
            value = row[key]
            return json.loads(value) if isinstance(value, str) and value[:1] in "[{" else value
    if name.startswith("time.") or name in ("status", "case_id"):
        return None
    return get_key(row["scene"], name)


def write_plot(spec: dict, rows: list[dict], results: Path) -> Path:
    """One declared plot: y against x for the ok cases, a curve (or marker set) per series value."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if spec["kind"] == "wedge_map":
        return write_wedge_map(spec, rows, results)
    if spec["kind"] in ("force_curves", "sweep", "jam_map"):
        from femcontact.study import snap_fit_report

        return getattr(snap_fit_report, f"write_{spec['kind']}")(spec, rows, results, column)
    x, y, series = spec["x"], spec["y"], spec["series"]
    groups: dict = {}
    for row in rows:
        if row["status"] != "ok":
            continue
        xv, yv = column(row, x), column(row, y)
        if isinstance(xv, (int, float)) and isinstance(yv, (int, float)) and math.isfinite(yv):
            value = column(row, series) if series else ""
            order = (0, value, "") if isinstance(value, (int, float)) else (1, 0, _label(value))
            groups.setdefault((order, _label(value)), []).append((xv, yv))
    if rows and not groups:
        known = sorted(set(rows[0]) - {"scene"})
        raise InputError(f"[[plot]] {y} against {x}: no ok case has numbers for both (columns: {', '.join(known)}, "
                         "or any scene key)")
    figure, axes = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    for (_, label), points in sorted(groups.items()):
        points.sort()
        style = "o-" if spec["kind"] == "line" else "o"
        axes.plot(*zip(*points), style, label=f"{series} = {label}" if series else None, markersize=4)
    axes.set(xlabel=x, ylabel=y, title=spec["title"] or f"{y} against {x}",
             xscale="log" if spec["logx"] else "linear", yscale="log" if spec["logy"] else "linear")
    axes.grid(True, alpha=0.3)
    if series:
        axes.legend()
    path = results / (spec["file"] or re.sub(r"[^\w.-]+", "_", f"{y}_vs_{x}") + ".png")
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def write_wedge_map(spec: dict, rows: list[dict], results: Path) -> Path:
    """Simulated wedged / not wedged (filled circle / cross; green when it agrees with the analytic
    condition l_crit <= l_d <= mu d, red when not) in the plane of two columns, with the analytic
    bounds drawn: x = 1 and y = 1 for the normalised map (depth_over_l_crit, depth_over_l_max);
    for y = peg.insertion_depth against clearance_ratio or contact.mu, the curves l_crit and
    l_max = mu d for the most common peg width (other widths are left out), one per value of the
    parameter not on the axis. Needs the metrics `wedged` and `analytic_wedged` (femcontact.wedging)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    x, y = spec["x"], spec["y"]
    points = []
    for row in rows:
        if row["status"] != "ok":
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
    figure, axes = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
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
        else:
            axes.plot(grid, grid * d, "k:", label="l_max = mu d")
            for D in sorted({column(p[4], "hole.width") for p in points}):
                axes.axhline(math.sqrt(D * D - d * d), color="k", linestyle="--", label=f"l_crit (D = {D:g})")
        axes.set_ylim(0, max(p[1] for p in points) * 1.15)
    agree = sum(p[2] == p[3] for p in points)
    axes.set(xlabel=x, ylabel=y, title=(spec["title"] or f"wedge map: {y} against {x}")
             + f"\nagreement with the analytic condition: {agree}/{len(points)}",
             xscale="log" if spec["logx"] else "linear", yscale="log" if spec["logy"] else "linear")
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7)
    path = results / (spec["file"] or re.sub(r"[^\w.-]+", "_", f"wedge_map_{y}_vs_{x}") + ".png")
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def wedge_table(rows: list[dict]) -> list[str]:
    """Markdown lines: agreement of the simulated `wedged` with `analytic_wedged`, overall, away from
    the bounds and near them (`near_boundary`), and the disagreeing cases. Empty without those metrics."""
    cases = [row for row in rows if row["status"] == "ok"
             and isinstance(column(row, "wedged"), (int, float)) and isinstance(column(row, "analytic_wedged"), (int, float))]
    if not cases:
        return []

    def rate(subset):
        n = len(subset)
        k = sum(bool(column(r, "wedged")) == bool(column(r, "analytic_wedged")) for r in subset)
        return f"{k}/{n}" + (f" ({100 * k / n:.0f} %)" if n else "")

    near = [r for r in cases if column(r, "near_boundary")]
    far = [r for r in cases if not column(r, "near_boundary")]
    lines = ["## Wedge map: simulated against l_crit <= l_d <= mu d", "",
             "| cases | agree |", "|---|---|", f"| all | {rate(cases)} |",
             f"| away from the bounds | {rate(far)} |", f"| near a bound (within 5 % of mu d) | {rate(near)} |", ""]
    wrong = [r for r in cases if bool(column(r, "wedged")) != bool(column(r, "analytic_wedged"))]
    if wrong:
        lines += ["Disagreements:", "", "| case | d | D | mu | l_d | l_crit | l_max | simulated | reason | residual A |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for r in wrong:
            lines.append("| " + " | ".join(_cell(v) for v in (
                r["case_id"], column(r, "peg.width"), column(r, "hole.width"), column(r, "contact.mu"),
                column(r, "peg.insertion_depth"), column(r, "l_crit"), column(r, "l_max"),
                bool(column(r, "wedged")), column(r, "wedge_reason"), column(r, "residual_force_A"))) + " |")
        lines.append("")
    return lines


def _label(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def write_snapshots(study, rows: dict) -> list[Path]:
    """Stress pictures of the ok cases the study selects; a case without fields.npz is skipped with a note."""
    from femcontact.outputs import snapshot

    settings, paths = study.snapshots, []
    for case in study.cases:
        if not any(_matches(case.scene, flatten(selector)) for selector in settings["select"]):
            continue
        if case.id not in rows or rows[case.id]["status"] != "ok":
            print(f"  (no snapshot of {case.id}: no ok result)", file=sys.stderr)
            continue
        fields = case.dir / "fields.npz"
        if not fields.exists():
            print(f"  (no snapshot of {case.id}: {fields} missing; does the solver write it?)", file=sys.stderr)
            continue
        (study.results / "snapshots").mkdir(exist_ok=True)
        path = study.results / "snapshots" / f"{case.id}.png"
        snapshot.render(fields, path, zoom=settings["zoom"] or None, scale=settings["scale"],
                        zoom_radius=settings["zoom_radius"])
        paths.append(path)
    return paths


def _matches(scene: dict, selector: dict) -> bool:
    def same(a, b):
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
        return a == b

    return all(same(get_key(scene, key), value) for key, value in selector.items())


def write_summary(study, columns: list[str], rows: list[dict], plots, snapshots) -> Path:
    """results/NAME/summary.md: counts, the table of cases, the pictures."""
    shown = [c for c in columns if c not in ("python", "dolfinx", "petsc4py", "numpy", "mpi4py", "git_commit")]
    ok = sum(row["status"] == "ok" for row in rows)
    description = [study.settings["description"], ""] if study.settings["description"] else []
    lines = [f"# Study {study.settings['name']}", "", *description,
             f"{len(study.cases)} cases: {ok} ok, {len(rows) - ok} failed, {len(study.cases) - len(rows)} not run. "
             f"Study file `{study.path}`; data in `results.csv` and `results.sqlite`.", ""]
    if rows:
        commits = sorted({str(row.get("git_commit")) for row in rows})
        lines += [f"Code: git {', '.join(commits)}; dolfinx {rows[0].get('dolfinx')}, "
                  f"python {rows[0].get('python')}.", "",
                  "| " + " | ".join(shown) + " |", "|" + "---|" * len(shown)]
        lines += ["| " + " | ".join(_cell(row.get(c)) for c in shown) + " |" for row in rows]
    lines += [""] + wedge_table(rows)
    from femcontact.study.snap_fit_report import table as snap_fit_table

    lines += [""] + snap_fit_table(rows, column)
    lines += [""] + [f"![{p.stem}]({p.name})" for p in plots]
    lines += [""] + [f"![{p.stem}](snapshots/{p.name})" for p in snapshots]
    path = study.results / "summary.md"
    path.write_text("\n".join(lines).rstrip() + "\n")
    return path


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value).replace("|", "\\|").replace("\n", " ")
