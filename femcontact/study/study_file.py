"""A study file: its schema, the sweep expanded into cases, and the scene of a case as TOML.

A study file names a base scene, inline overrides and a sweep (a grid, zipped lists and
explicit cases, over dotted scene keys such as `steps.1.force`). Every case is resolved and
validated before anything runs; its id is the hash of its resolved scene
(`femcontact.config.scene.case_id`), so a study's cases are found again when it is run again
(study/runner.py). See docs/studies.md.
"""
import itertools
import json
import math
import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

from femcontact.config.scene import apply_overrides, case_id, read_toml
from femcontact.families import family_of, plot_kinds, resolve_scene
from femcontact.config.schema import Field, TableList, get_key, set_key, validate
from femcontact.errors import InputError

_TABLE = Field("any", {}, "a table", check=lambda v: None if isinstance(v, dict) else "must be a table")
_TABLES = Field("any", [], "an array of tables",
                check=lambda v: None if isinstance(v, list) and all(isinstance(t, dict) for t in v)
                else "must be an array of tables")

SCHEMA = {
    "study": {
        "name": Field("str", doc="study name: results go to results/NAME/",
                      check=lambda v: None if v and "/" not in v and not v.startswith(".") else "not a plain name"),
        "description": Field("str", "", "what the study is for"),
        "scene": Field("str", doc="base scene file, relative to the study file"),
        "jobs": Field("int", 0, "cases run at once; 0 = cores // ranks_per_case", min=0),
        "ranks_per_case": Field("int", 1, "MPI ranks per case", min=1),
        "time_limit": Field("float", 600.0, "seconds per case; a case past it is killed and recorded failed",
                            positive=True),
        "launcher": Field("str", "mpirun -n {ranks}", "command prefix that starts an MPI job of {ranks} ranks",
                          check=lambda v: check_launcher(v)),
        "shared_steps": Field("int", 0, "> 0: cases agreeing on their first steps compute them once", min=0),
        "workers": Field("bool", True, "one-rank cases under the default launcher run in warm worker processes "
                         "(one per job, importing femcontact once); false: a fresh launcher process per case"),
    },
    "scene": _TABLE,
    "sweep": {
        "grid": Field("any", {}, "key = [values]: every combination", check=lambda v: _check_lists(v, False)),
        "zip": Field("any", {}, "key = [values]: lists of one length, taken together",
                     check=lambda v: _check_lists(v, True)),
        "cases": _TABLES,
    },
    "plot": TableList({
        "x": Field("str", doc="column on the x axis (a swept or scene key, a metric, time.PHASE)"),
        "y": Field("str", doc="column on the y axis"),
        "series": Field("str", "", "column whose values make separate curves"),
        "kind": Field("str", "line", "line, scatter, or a study family's plot kind (femcontact.families): "
                      + ", ".join(plot_kinds()), choices=("line", "scatter", *plot_kinds())),
        "select": Field("any", {}, "force_curves, sweep: only cases whose scene has key = value (or one of a list)",
                        check=lambda v: None if isinstance(v, dict) else "must be a table"),
        "logx": Field("bool", False, "logarithmic x axis"),
        "logy": Field("bool", False, "logarithmic y axis"),
        "title": Field("str", "", "plot title"),
        "file": Field("str", "", "PNG file name in results/NAME/ (default Y_vs_X.png)"),
    }, "plots written by `femcontact report`", default=[]),
    "snapshots": {
        "select": _TABLES,
        "field": Field("str", "von_mises", "field shown", choices=("von_mises",)),
        "zoom": Field("any", "", "named point of the fields file, or [x, y(, z), radius]",
                      check=lambda v: None if isinstance(v, str) or (
                          isinstance(v, list) and len(v) in (3, 4) and all(isinstance(x, (int, float)) for x in v)
                          and v[-1] > 0)
                      else "expected a name or [x, y(, z), radius] with radius > 0"),
        "zoom_radius": Field("float", 0.0, "zoom radius around a named point; 0 = 1/8 of the model size", min=0.0),
        "scale": Field("float", 1.0, "displacement magnification", min=0.0),
    },
    "animation": {
        "select": Field("any", [], "cases filmed in the report (femcontact animate), as [snapshots] selects them; "
                        "they run with outputs.fields = true",
                        check=lambda v: None if isinstance(v, list) and all(isinstance(t, dict) and t for t in v)
                        else "must be an array of non-empty tables"),
        "scale": Field("float", 1.0, "displacement magnification of the films", min=0.0),
        "every": Field("int", 1, "film every N-th increment (outputs.every of the filmed cases)", min=1),
    },
    "report": {
        "columns": Field("strs", [], "headline columns of summary.md and index.html (at most MAX_COLUMNS; "
                         "default: swept keys, status, the family's primary metrics, wall time)",
                         check=lambda v: _check_columns(v)),
    },
}
MAX_COLUMNS = 25  # a wider table is not readable; every column stays in results.csv


def _check_columns(columns: list[str]) -> str | None:
    bad = [c for c in columns if not c.strip()] or [c for i, c in enumerate(columns) if c in columns[:i]]
    if bad:
        return f"column {bad[0]!r} is empty or repeated"
    if len(columns) > MAX_COLUMNS:
        return f"{len(columns)} columns, at most {MAX_COLUMNS} (the rest is in results.csv)"
    return None


def flatten(table: dict, prefix: str = "") -> dict:
    """{'peg': {'width': 1}} -> {'peg.width': 1} (TOML turns unquoted dotted keys into sub-tables)."""
    flat = {}
    for key, value in table.items():
        if isinstance(value, dict):
            flat.update(flatten(value, f"{prefix}{key}."))
        else:
            flat[prefix + key] = value
    return flat


def _check_lists(table, same_length: bool) -> str | None:
    if not isinstance(table, dict):
        return "must be a table of key = [values]"
    lists = flatten(table)
    bad = [key for key, values in lists.items() if not isinstance(values, list) or not values]
    if bad:
        return f"{bad[0]} must be a non-empty list of values"
    if same_length and len({len(values) for values in lists.values()}) > 1:
        return "zipped lists must have one length: " + ", ".join(f"{k} has {len(v)}" for k, v in lists.items())
    return None


def check_launcher(launcher: str) -> str | None:
    """A complaint about a launcher command, or None: it must format with {ranks} alone and name a program."""
    import shutil

    try:
        words = shlex.split(launcher.format(ranks=1))
    except (KeyError, IndexError, ValueError) as error:
        return f"cannot be read ({type(error).__name__}: {error}); the only placeholder is {{ranks}}"
    if words and shutil.which(words[0]) is None:
        return f"{words[0]!r}: no such program"
    return None


@dataclass
class Case:
    """One case of a study: its swept parameters, resolved scene and directory."""
    params: dict
    scene: dict
    id: str
    dir: Path
    prefix: "Case | None" = None  # the shared-prefix computation it restarts from

    @property
    def is_prefix(self) -> bool:
        """A shared prefix (results/NAME/prefix/ID), not a case of the study."""
        return self.dir.parent.name == "prefix"


@dataclass
class Study:
    """A loaded study: settings, cases (in sweep order), swept keys and result paths."""
    path: Path
    settings: dict
    cases: list[Case]
    keys: list[str]
    results: Path
    plots: list = field(default_factory=list)
    snapshots: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)
    base: dict = field(default_factory=dict)  # the base scene with the study's and --set values, unresolved
    sweep: dict = field(default_factory=dict)
    count: int = 0  # parameter sets of the sweep (cases before duplicates are merged)
    animation: dict = field(default_factory=dict)

    @property
    def database(self) -> Path:
        return self.results / "results.sqlite"


def expand(sweep: dict) -> Iterator[dict]:
    """Parameter sets of a sweep, one at a time: grid (product) x zip (together), then the
    explicit cases. An empty sweep is the base scene alone."""
    grid, zipped = flatten(sweep.get("grid", {})), flatten(sweep.get("zip", {}))
    explicit = [flatten(case) for case in sweep.get("cases", [])]
    if not grid and not zipped:
        yield from explicit or [{}]
        return
    zip_sets = [dict(zip(zipped, values)) for values in zip(*zipped.values())] or [{}]
    for values in itertools.product(*grid.values()):
        for z in zip_sets:
            yield {**dict(zip(grid, values)), **z}
    yield from explicit


def count_cases(sweep: dict) -> int:
    """How many parameter sets `expand(sweep)` yields, without making them."""
    grid, zipped = flatten(sweep.get("grid", {})), flatten(sweep.get("zip", {}))
    explicit = len(sweep.get("cases", []))
    if not grid and not zipped:
        return explicit or 1
    return math.prod(len(values) for values in grid.values()) * \
        (len(next(iter(zipped.values()))) if zipped else 1) + explicit


def swept_keys(sweep: dict) -> list[str]:
    """The dotted scene keys a sweep sets, in the order of its parameter sets."""
    explicit = [key for case in sweep.get("cases", []) for key in flatten(case)]
    return list(dict.fromkeys([*flatten(sweep.get("grid", {})), *flatten(sweep.get("zip", {})), *explicit]))


def load_study(path, overrides=(), results_root="results", max_cases=None, resolve_cases=True) -> Study:
    """Read and validate a study file and resolve every case; raises InputError naming bad cases.

    A sweep of more than `max_cases` cases (None: no limit) is refused before any is made. With
    `resolve_cases` false the cases are left to `iter_cases` (one at a time, e.g. for --list)."""
    path = Path(path)
    try:
        raw = validate(read_toml(path), SCHEMA)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    settings = raw["study"]
    base = read_toml(path.parent / settings["scene"])
    for key, value in flatten(raw["scene"]).items():
        set_key(base, key, value)
    apply_overrides(base, overrides)  # --set changes the base scene; the sweep still varies its own keys
    count = count_cases(raw["sweep"])
    if max_cases is not None and count > max_cases:
        raise InputError(f"{path}: the sweep makes {count} cases, more than the limit of {max_cases}; nothing was "
                         f"run (pass --max-cases {count} to run them all, or --list to see them)")
    results = Path(results_root) / settings["name"]
    study = Study(path, settings, [], swept_keys(raw["sweep"]), results, raw["plot"], raw["snapshots"],
                  raw["report"], base=base, sweep=raw["sweep"], count=count, animation=raw["animation"])
    _check_scene_once(study)
    if resolve_cases:
        make_cases(study)
    return study


def make_cases(study: Study) -> None:
    """Resolve every case of the study into `study.cases`, with their shared prefixes."""
    study.cases = list(iter_cases(study))
    if study.settings["shared_steps"]:
        attach_prefixes(study.cases, study.settings["shared_steps"], study.results)


def _check_scene_once(study: Study) -> None:
    """Refuse in one line a base scene that is invalid whatever the sweep sets: its error names
    no swept key and the first case fails with the same error."""
    try:
        resolve_scene(study.base)
        return
    except InputError as error:
        message = str(error)
    forms = {form for key in study.keys for form in (key, re.sub(r"\.(\d+)", r"[\1]", key))}
    if any(form in message for form in forms):
        return  # the sweep may mend it; each case says
    try:
        resolve_scene(_case_data(study.base, next(expand(study.sweep))))
    except InputError as error:
        if str(error) == message:
            raise InputError(f"{study.path}: {study.count} invalid case(s), nothing was run: {message} (the scene "
                             f"{study.settings['scene']} with the study's values, whatever the sweep sets)") from None


def _case_data(base: dict, params: dict) -> dict:
    data = json.loads(json.dumps(base))
    for key, value in params.items():
        set_key(data, key, value)
    return data


def iter_cases(study: Study) -> Iterator[Case]:
    """The study's distinct cases in sweep order, resolved one at a time; once all are made,
    raises InputError listing the invalid ones, grouped by error."""
    problems, seen = {}, set()
    for params in expand(study.sweep):
        try:
            scene = resolve_scene(_case_data(study.base, params))
            if any(key.endswith("_type") for key in scene.get("solver", {}).get("petsc_options", {})):
                from femcontact.solver.linear import check_petsc_options  # PETSc is imported only for these

                check_petsc_options(scene["solver"]["petsc_options"])
            if "outputs" in scene and any(matches(scene, flatten(t)) for t in study.animation["select"]):
                scene["outputs"].update(fields=True, every=study.animation["every"])  # filmed in the report
        except InputError as error:
            problems.setdefault(str(error), []).append(params)
            continue
        identity = case_id(scene)
        if identity not in seen:
            seen.add(identity)
            yield Case({key: get_key(scene, key) for key in study.keys}, scene, identity,
                       study.results / "cases" / identity)
    if problems:
        invalid = sum(map(len, problems.values()))
        lines = [f"case {describe_params(cases[0])}: {message}" if len(cases) == 1 else
                 f"{message} ({'every case' if len(cases) == study.count else f'{len(cases)} cases'}: "
                 + "; ".join(describe_params(params) for params in cases[:3]) + ("; ..." if len(cases) > 3 else "") + ")"
                 for message, cases in problems.items()]
        raise InputError(f"{study.path}: {invalid} invalid case(s), nothing was run:\n  " + "\n  ".join(lines))


def matches(scene: dict, selector: dict) -> bool:
    """Does the scene have every dotted key of `selector` at its value (numbers to 1e-9)?"""
    def same(a, b):
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
        return a == b

    return all(same(get_key(scene, key), value) for key, value in selector.items())


def attach_prefixes(cases: list[Case], shared: int, results: Path) -> None:
    """Give every case with more than `shared` steps the prefix case it restarts from."""
    prefixes = {}
    for case in cases:
        if len(case.scene["steps"]) <= shared:
            continue
        family = family_of(case.scene)
        omitted = family.prefix_omits if family else ()  # read only after the shared steps
        scene = {key: value for key, value in case.scene.items() if key not in omitted}
        scene["steps"] = case.scene["steps"][:shared]
        if "outputs" in scene:  # a filmed case shares its prefix with the others: the prefix writes no time series
            scene["outputs"] = {**scene["outputs"], "fields": False, "every": 1}
        identity = case_id(scene)
        if identity not in prefixes:
            prefixes[identity] = Case({}, scene, identity, results / "prefix" / identity)
        case.prefix = prefixes[identity]


def describe_params(params: dict) -> str:
    return ", ".join(f"{key}={value!r}" for key, value in params.items()) or "(base scene)"


def to_toml(scene: dict) -> str:
    """TOML text of a resolved scene: scalars, then [tables], then [[arrays of tables]]."""
    lines = [f"{_key(k)} = {_value(v)}" for k, v in scene.items() if not _is_table(v) and not _is_tables(v)]
    for key, value in scene.items():
        if _is_table(value):
            lines += ["", f"[{_key(key)}]"] + _table_lines(value)
    for key, value in scene.items():
        if _is_tables(value):
            for item in value:
                lines += ["", f"[[{_key(key)}]]"] + _table_lines(item)
    return "\n".join(lines) + "\n"


def _is_table(value) -> bool:
    return isinstance(value, dict) and bool(value)


def _is_tables(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _table_lines(table: dict, prefix: str = "") -> list[str]:
    lines = []
    for key, value in table.items():
        if _is_table(value):
            lines += _table_lines(value, f"{prefix}{_key(key)}.")
        else:
            lines.append(f"{prefix}{_key(key)} = {_value(value)}")
    return lines


def _key(key: str) -> str:
    return key if key and all(c.isalnum() or c in "_-" for c in key) else json.dumps(key)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_value, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")
