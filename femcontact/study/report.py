"""`femcontact report STUDY.toml`: plots, stress snapshots and a summary of a study.

Everything goes to results/NAME/: the plots the study declares ([[plot]], PNG),
snapshots/CASE_ID.png for the cases [snapshots] selects, animations/CASE_ID.mp4 and .gif
(`femcontact animate`) for the cases [animation] selects, and the summary twice, as
summary.md and index.html (the same table and pictures, for a browser). The table shows
the headline columns ([report] columns, or by default the family's primary metrics, swept
keys, status, case id and wall time), the answer first; labels with units from
femcontact.outputs.units; every
column is in results.csv and results.sqlite. The database is rebuilt from the case
directories first, so the report shows exactly what is on disk.
"""
import html
import json
import math
import os
import re
import sys
import textwrap
from collections import Counter
from pathlib import Path

from femcontact import families
from femcontact.config.schema import get_key
from femcontact.errors import InputError
from femcontact.io import make_dir, write_atomic, write_text_atomic
from femcontact.outputs import units
from femcontact.outputs.figures import plain_log_ticks
from femcontact.outputs.result import status_counts
from femcontact.outputs.tables import markdown_table
from femcontact.study.study_file import MAX_COLUMNS, flatten, load_study, matches


def add_arguments(parser):
    parser.add_argument("study", help="study file (TOML)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="the same base-scene overrides given to `femcontact study`")
    parser.add_argument("--results", default="results", help="results root (default: results)")


def command(args) -> int:
    from femcontact.study.database import Database

    study = load_study(args.study, args.set, args.results)
    make_dir(study.results)
    database = Database(study.database, study.keys)
    try:
        database.rebuild(study.cases)
        csv = database.export_csv(study.results / "results.csv")
        rows = database.rows()
        columns = database.csv_columns()
    finally:
        database.close()
    for row in rows:
        row["scene"] = json.loads(row["scene"]) if row["scene"] else {}
    columns = headline_columns(study, columns, rows)
    plots = [write_plot(spec, rows, study.results, study.keys) for spec in study.plots]
    snapshots = write_snapshots(study, {row["case_id"]: row for row in rows})
    films = write_animations(study, {row["case_id"]: row for row in rows})
    family = families.study_family(case.scene for case in study.cases)
    before = []  # the family's own tables, before the per-case table
    if family and family.report:
        written, before = family.report(study)
        plots += written
    after = family.tables(rows, column) if family and family.tables else []
    document = summary(study, columns, rows, plots, snapshots, before, films, after)
    markdown = write_markdown(document, study.results / "summary.md")
    page = write_html(document, study.results / "index.html", f"Study {study.settings['name']}")
    print(f"study {study.settings['name']}: {len(rows)} of {len(study.cases)} cases have results")
    print(f"  summary:   {markdown} and {page} ({len(columns)} columns)")
    print(f"  data:      {csv} and {study.database} (every column)")
    for path in plots:
        print(f"  plot:      {path}")
    for path in snapshots:
        print(f"  snapshot:  {path}")
    for path in films:
        print(f"  animation: {path}")
    return 0


RUN_COLUMNS = ("status", "reason", "case_id", "wall", "wall_time_s", "dofs", "ranks")
"""Columns about the run rather than its answer or its inputs: last in the summary table."""


def headline_columns(study, csv_columns: list[str], rows: list[dict]) -> list[str]:
    """The summary table's columns, the answer first (`answer_first`): [report] columns (each checked
    against the results), or the default: the family's primary metrics, the swept keys, status, case
    id, wall time (and the failure reason when a case failed), at most MAX_COLUMNS."""
    declared = study.report.get("columns") or []
    if declared:
        for name in declared:
            if rows and name not in csv_columns and all(get_key(row["scene"], name) is None for row in rows):
                raise InputError(f"{study.path}: [report] columns: {name!r} is neither a column of results.csv "
                                 f"nor a scene key (columns: {', '.join(csv_columns)})")
        return answer_first(list(declared), study.keys, rows)
    failed = any(row["status"] != "ok" for row in rows)
    default = [*families.primary_columns(csv_columns), *study.keys, "status", "case_id", "wall"] + \
        (["reason"] if failed else [])
    return answer_first(list(dict.fromkeys(default))[:MAX_COLUMNS], study.keys, rows)


def answer_first(columns: list[str], keys: list[str], rows: list[dict]) -> list[str]:
    """The columns in three groups, each in its given order: results (metrics), then inputs (swept
    keys and other scene keys), then the run's bookkeeping (RUN_COLUMNS, time.PHASE)."""
    def group(name: str) -> int:
        if name in RUN_COLUMNS or name.startswith("time."):
            return 2
        if name in keys:
            return 1
        if any(name in row or f"metric.{name}" in row for row in rows):  # a metric
            return 0
        return 1 if any(get_key(row["scene"], name) is not None for row in rows) else 0

    return sorted(columns, key=group)


def column(row: dict, name: str):
    """A row's value for a column, a metric name or any scene key; lists stored as JSON are decoded."""
    for key in (name, f"metric.{name}"):
        if key in row:
            value = row[key]
            return json.loads(value) if isinstance(value, str) and value[:1] in "[{" else value
    if name.startswith("time.") or name in ("status", "case_id"):
        return None
    return get_key(row["scene"], name)


def curves(spec: dict, rows: list[dict], keys: list[str]) -> list[dict]:
    """The curves of a line or scatter plot of y against x over the ok cases, each
    {'label', 'points': [(x, y)] sorted by x, 'joined': draw a line, 'reference': bool}.

    kind "line": a line joins only cases that differ in x alone, i.e. agree on every other swept
    key (and on `series`); each such set is one curve, labelled by the keys where it differs from
    the reference, the most common value of each (that curve comes first, labelled with them; in
    a full grid, where no value is the most common, each curve is labelled with its values). A
    case with no partner is a lone marker. kind "scatter": one marker set per value of `series`."""
    x, y, series = spec["x"], spec["y"], spec["series"]
    points = []
    for row in rows:
        xv, yv = column(row, x), column(row, y)
        if row["status"] == "ok" and _number(xv) and _number(yv) and math.isfinite(yv):
            points.append((row, xv, yv))
    if rows and not points:
        known = sorted(set(rows[0]) - {"scene"})
        raise InputError(f"[[plot]] {y} against {x}: no ok case has numbers for both (columns: {', '.join(known)}, "
                         "or any scene key)")
    others = [k for k in dict.fromkeys(([series] if series else []) + (keys if spec["kind"] == "line" else []))
              if k != x]
    counts = [Counter(json.dumps(column(row, k)) for row, _, _ in points).most_common() for k in others]
    varying = [k for k, count in zip(others, counts) if len(count) > 1]
    # the reference: the most common value of every key, if no other value is as common (not in a full grid)
    unique = all(len(count) < 2 or count[0][1] > count[1][1] for count in counts)
    reference = tuple(count[0][0] for count in counts) if points and unique else None
    groups: dict = {}
    for row, xv, yv in points:
        groups.setdefault(tuple(json.dumps(column(row, k)) for k in others), []).append((xv, yv))
    out = []
    for group, xy in sorted(groups.items(), key=lambda item: (item[0] != reference, [_order(v) for v in item[0]])):
        is_reference = group == reference and len(groups) > 1
        shown = [k for k, v, r in zip(others, group, reference) if v != r] if reference and not is_reference \
            else varying
        name = "; ".join(units.value_label(k, json.loads(v)) for k, v in zip(others, group) if k in shown)
        out.append({"label": ("reference: " if is_reference else "") + name, "points": sorted(xy),
                    "joined": spec["kind"] == "line" and len({p[0] for p in xy}) > 1, "reference": is_reference})
    return out


def write_plot(spec: dict, rows: list[dict], results: Path, keys: list[str]) -> Path:
    """One declared plot (PNG): the curves of `curves`, or a wedge map; axis labels with units."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    family_plot = families.plot_kind(spec["kind"])
    if family_plot:
        return family_plot(spec, rows, results, column)
    x, y = spec["x"], spec["y"]
    figure, axes = plt.subplots(figsize=(10, 4.8), layout="constrained")
    colours = iter(plt.get_cmap("tab10").colors * 10)
    lines = curves(spec, rows, keys)
    for curve in lines:
        style = {"color": "black", "linewidth": 2.2} if curve["reference"] else {"color": next(colours)}
        axes.plot(*zip(*curve["points"]), "o-" if curve["joined"] else "o", markersize=4,
                  label=textwrap.fill(curve["label"], 45), **style)
    axes.set(xlabel=units.label(x), ylabel=units.label(y), xscale="log" if spec["logx"] else "linear",
             yscale="log" if spec["logy"] else "linear")
    axes.set_title(textwrap.fill(spec["title"] or f"{units.label(y)} against {units.label(x)}", 70), fontsize=11)
    plain_log_ticks(axes, spec)
    axes.grid(True, alpha=0.3)
    if any(curve["label"] for curve in lines):
        axes.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0,
                    title="joined: cases differing in x only" if spec["kind"] == "line" else None,
                    title_fontsize=7)
    path = results / (spec["file"] or re.sub(r"[^\w.-]+", "_", f"{y}_vs_{x}") + ".png")
    write_atomic(path, lambda stream: figure.savefig(stream, format="png", dpi=120), binary=True)
    plt.close(figure)
    return path


def _order(text: str) -> tuple:
    """Sort key of a JSON-encoded value: numbers by value, before anything else by text."""
    value = json.loads(text)
    return (0, value, "") if _number(value) else (1, 0, text)


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def write_snapshots(study, rows: dict) -> list[Path]:
    """Stress pictures of the ok cases the study selects; a case without fields.npz is skipped with a note."""
    from femcontact.outputs import snapshot

    settings, paths = study.snapshots, []
    for case in study.cases:
        if not any(matches(case.scene, flatten(selector)) for selector in settings["select"]):
            continue
        if case.id not in rows or rows[case.id]["status"] != "ok":
            print(f"  (no snapshot of {case.id}: no ok result)", file=sys.stderr)
            continue
        fields = case.dir / "fields.npz"
        if not fields.exists():
            print(f"  (no snapshot of {case.id}: {fields} missing; does the solver write it?)", file=sys.stderr)
            continue
        make_dir(study.results / "snapshots")
        path = study.results / "snapshots" / f"{case.id}.png"
        tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.png")  # rendered whole, then renamed
        try:
            snapshot.render(fields, tmp, zoom=settings["zoom"] or None, scale=settings["scale"],
                            zoom_radius=settings["zoom_radius"])
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        paths.append(path)
    return paths


def write_animations(study, rows: dict) -> list[Path]:
    """Films (MP4, and a GIF for summary.md) of the ok cases [animation] selects, in animations/;
    a case without a time series is skipped with a note."""
    from femcontact.outputs.animation import animate

    paths = []
    for case in study.cases:
        if not any(matches(case.scene, flatten(selector)) for selector in study.animation.get("select", [])):
            continue
        if case.id not in rows or rows[case.id]["status"] != "ok" or not (case.dir / "fields.xdmf").exists():
            print(f"  (no animation of {case.id}: no ok result with fields.xdmf)", file=sys.stderr)
            continue
        folder = make_dir(study.results / "animations")
        for made in animate(case.dir, scale=study.animation["scale"]):
            path = folder / f"{case.id}{made.suffix}"
            os.replace(made, path)
            paths.append(path)
    return paths


def summary(study, columns: list[str], rows: list[dict], plots, snapshots, family=(), films=(), after=()) -> list[tuple]:
    """The report as blocks ("h1" | "h2" | "p", text), ("table", header, rows), ("img", path, caption),
    ("video", MP4 path, GIF path, caption), written as Markdown and as HTML; `family`: the study
    family's own blocks, before the case table, `after`: those after it; `films`: the animations'
    MP4 and GIF paths."""
    counts = status_counts(rows)
    blocks = [("h1", f"Study {study.settings['name']}")]
    if study.settings["description"]:
        blocks.append(("p", study.settings["description"]))
    blocks.append(("p", f"{len(study.cases)} cases: {counts['ok']} ok, {counts['no_equilibrium']} without a static "
                        f"equilibrium of their load, {counts['failed']} failed, "
                        f"{len(study.cases) - len(rows)} not run. Study file `{study.path}`; every column "
                        "(all metrics, timings, versions) in `results.csv` and `results.sqlite`."))
    if rows:
        commits = sorted({str(row.get("git_commit")) for row in rows})
        blocks.append(("p", f"Code: git {', '.join(commits)}; dolfinx {rows[0].get('dolfinx')}, "
                            f"python {rows[0].get('python')}."))
        blocks += list(family)
        if family:
            blocks.append(("h2", "Cases"))
        blocks.append(("table", [units.label(c) for c in columns],
                       [[units.cell(column(row, c), c) for c in columns] for row in rows]))
    blocks += list(after)
    if plots:
        blocks.append(("h2", "Plots"))
        blocks += [("img", p.name, p.stem) for p in plots]
    by_id = {case.id: case for case in study.cases}
    if films:
        blocks.append(("h2", "Animations"))
        blocks += [("video", f"animations/{p.name}", f"animations/{p.stem}.gif", f"case {p.stem}: " + "; ".join(
            units.value_label(k, v) for k, v in by_id[p.stem].params.items()) + " (von Mises stress, both bodies, "
            "forces against time)") for p in films if p.suffix == ".mp4"]
    if snapshots:
        blocks.append(("h2", "Stress snapshots"))
        blocks += [("img", f"snapshots/{p.name}", f"case {p.stem}: " + "; ".join(
            units.value_label(k, v) for k, v in by_id[p.stem].params.items())) for p in snapshots]
    return blocks


def write_markdown(blocks: list[tuple], path: Path) -> Path:
    """summary.md of the report blocks."""
    lines = []
    for kind, *content in blocks:
        if kind in ("h1", "h2"):
            lines += [("# " if kind == "h1" else "## ") + content[0], ""]
        elif kind == "p":
            lines += [content[0], ""]
        elif kind == "table":
            lines += [*markdown_table(*content), ""]
        elif kind == "video":
            lines += [f"[![{content[2]}]({content[1]})]({content[0]})", ""]
        else:
            lines += [f"![{content[1]}]({content[0]})", ""]
    write_text_atomic(path, "\n".join(lines).rstrip() + "\n")
    return path


HTML_STYLE = """body { font-family: sans-serif; margin: 1.5em; color: #222; }
table { border-collapse: collapse; font-size: 13px; margin: 0.5em 0 1.5em; }
th, td { border: 1px solid #bbb; padding: 2px 6px; text-align: right; white-space: nowrap; }
th { background: #eee; position: sticky; top: 0; white-space: normal; max-width: 9em; vertical-align: bottom; }
td.text { text-align: left; }
.wide { overflow-x: auto; }
figure { margin: 1em 0 2em; }
img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 13px; color: #555; }"""


def write_html(blocks: list[tuple], path: Path, title: str) -> Path:
    """index.html of the report blocks: the same text, tables and pictures as summary.md."""
    parts = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
             f"<title>{html.escape(title)}</title>", f"<style>\n{HTML_STYLE}\n</style>", "</head>", "<body>"]
    for kind, *content in blocks:
        if kind in ("h1", "h2", "p"):
            parts.append(f"<{kind}>{_inline_html(content[0])}</{kind}>")
        elif kind == "table":
            header, body = content
            parts.append('<div class="wide"><table>')
            parts.append("<thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr></thead>")
            parts.append("<tbody>")
            for cells in body:
                parts.append("<tr>" + "".join(
                    f"<td>{html.escape(c)}</td>" if _numeric_text(c) else f'<td class="text">{html.escape(c)}</td>'
                    for c in cells) + "</tr>")
            parts.append("</tbody></table></div>")
        elif kind == "video":
            video, gif, caption = content
            parts.append(f'<figure><video src="{html.escape(video)}" controls loop muted preload="metadata" '
                         f'style="max-width: 100%"><img src="{html.escape(gif)}" alt="{html.escape(caption)}">'
                         f"</video><figcaption>{html.escape(caption)}</figcaption></figure>")
        else:
            source, caption = content
            parts.append(f'<figure><img src="{html.escape(source)}" alt="{html.escape(caption)}">'
                         f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    parts += ["</body>", "</html>"]
    write_text_atomic(path, "\n".join(parts) + "\n")
    return path


def _inline_html(text: str) -> str:
    """Escaped text with `code` spans."""
    return re.sub(r"`([^`]*)`", r"<code>\1</code>", html.escape(text))


def _numeric_text(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


