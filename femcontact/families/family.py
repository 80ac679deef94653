"""What a study family declares about itself: one `Family` object per family package.

A family is a kind of study (wedging, insertion, dislodging, ...). Its package builds one
`Family` and the registry (`femcontact/families/__init__.py`) lists it; the case runner, scene
resolution, the study report and `make accuracy` find everything about the family here, so
none of them names a family. Every field but `name` is optional: a family of contact scenes
that adds nothing runs like any contact scene.
"""
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable


@dataclass(frozen=True)
class Accuracy:
    """The family's rows in `make accuracy` (docs/accuracy.md)."""
    rows: str
    """'module:function' returning (rows, notes): error against wall time per setting of each knob."""
    errors: tuple[str, ...]
    """The error columns of its table."""
    plots: tuple[tuple[str, str], ...]
    """(error column, plot title) per Pareto plot."""
    default: bool = True
    """Measured by a plain `make accuracy`; otherwise only when named with `--problems`."""


@dataclass(frozen=True)
class Gathering:
    """A report across several of the family's studies, written to results/NAME/ by
    `python -m femcontact.study.gathering NAME` once they have run."""
    name: str
    studies: tuple[Path, ...]
    """The study files it reads: the cases each file makes now, not every case directory on disk."""
    write: Callable[[dict, Path], None]
    """write(cases, out): from `cases`, {study file's stem: [(case, metrics) of its cases that ended ok]},
    the report's files written into `out`."""


@dataclass(frozen=True)
class Family:
    """One study family: what it adds to scenes, how its cases run, what its report shows.

    Scenes: a family either claims contact scenes (`claims`, `kind` = 'contact': the contact
    schema of femcontact.config.scene, no keys of its own) or owns scene kinds (`kinds`), each
    resolved by `resolve` from raw scene data (its schema additions, defaults and checks on top
    of the contact schema's validation)."""
    name: str
    doc: str = ""
    """Its page in docs/."""
    kinds: tuple[str, ...] = ()
    """Scene kinds (`kind = ...` in a scene file) the family owns, resolved by `resolve`."""
    resolve: Callable[[dict], dict] | None = None
    """Raw scene data of one of `kinds` (overrides applied) -> the resolved scene; InputError naming the key."""
    claims: Callable[[dict], bool] | None = None
    """Whether a resolved contact scene (kind 'contact') is one of this family's (e.g. by geometry)."""
    schema_sections: Callable[[], list[tuple[str, list[tuple], str]]] | None = None
    """(title, table rows (`femcontact.config.schema.describe`), example) of its scene keys for docs/scenes.md
    (femcontact.families.docs)."""
    scene_factory: Callable[..., dict] | None = None
    """Builds raw scene data in code (e.g. the Hertz benchmark at one contact-zone size)."""
    run_case: Callable[..., dict] | None = None
    """run_case(scene, case_dir, checkpoint, restart) for a scene of its own kinds; None: the contact run."""
    prefix_omits: tuple[str, ...] = ()
    """Scene tables read only after a study's shared steps: a shared prefix's scene leaves them out,
    so cases that differ only in them compute their first steps once."""
    metrics: Callable | None = None
    """metrics(simulation) -> dict: the family's metrics of a finished contact run."""
    outcome_metrics: Callable[[dict], dict] | None = None
    """outcome_metrics(scene) -> dict: its metrics of a run whose load has no static equilibrium."""
    primary_columns: tuple[str, ...] = ()
    """Headline metrics, the report's default columns (picked when the first is among a study's columns)."""
    plots: dict[str, Callable] = field(default_factory=dict)
    """Plot kinds of `[[plot]] kind = ...`: function(spec, rows, results, column) -> the PNG's path."""
    report: Callable | None = None
    """report(study) -> (plots written, summary blocks shown before the case table)."""
    tables: Callable | None = None
    """tables(rows, column) -> summary blocks shown after the case table."""
    gatherings: tuple[Gathering, ...] = ()
    """Its reports across several of its studies."""
    accuracy: Accuracy | None = None
    """Its rows in `make accuracy`."""
