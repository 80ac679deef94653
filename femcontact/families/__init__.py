"""The study families and their registry: one package per family, one `Family` object each
(femcontact/families/family.py says what it declares).

`FAMILIES` lists them; everything that depends on a scene's family looks it up here: the case
runner (`femcontact.families.case`), scene resolution (`resolve_scene`, `load_scene`: the
contact schema of femcontact.config plus the family's own kinds), the study report (plot kinds,
headline columns, the family's tables, the reports across studies) and `make accuracy`. Adding a family is a package
`femcontact/families/NAME/` that builds its `FAMILY` and one line in `FAMILIES`.
Importing the registry is cheap (no DOLFINx, no MPI): a family's heavy modules load when run.
"""
import json

from femcontact.config.scene import apply_overrides, read_toml, resolve_contact
from femcontact.errors import InputError
from femcontact.families import dislodging, hertz, insertion, rcc, snap_fit, wedging
from femcontact.families.family import Accuracy, Family, Gathering

FAMILIES = [hertz.FAMILY, wedging.FAMILY, insertion.FAMILY, snap_fit.FAMILY, dislodging.FAMILY, rcc.FAMILY]

CONTACT_PRIMARY = ("max_von_mises", "newton_iterations")
"""Headline metrics of a contact study no family's headline metrics match."""

__all__ = ["Accuracy", "FAMILIES", "Family", "Gathering", "family_of", "gatherings", "load_scene", "plot_kind",
           "plot_kinds", "primary_columns", "resolve_scene", "study_family"]


def _owner(kind: str) -> Family:
    for family in FAMILIES:
        if kind in family.kinds:
            return family
    kinds = ["contact", *(k for family in FAMILIES for k in family.kinds)]
    raise InputError(f"kind = {kind!r}: not allowed, expected one of {', '.join(map(repr, kinds))}")


def family_of(scene: dict) -> Family | None:
    """The family of a resolved scene: the owner of its kind, else the family that claims the
    contact scene; None for a contact scene no family claims (a plain contact run)."""
    if scene["kind"] != "contact":
        return _owner(scene["kind"])
    return next((family for family in FAMILIES if family.claims and family.claims(scene)), None)


def resolve_scene(data: dict, overrides=()) -> dict:
    """Validate raw scene data (plus overrides, see config.scene.apply_overrides) and return the
    resolved scene: a contact scene by the contact schema, any other kind by its family."""
    data = json.loads(json.dumps(data))  # deep copy, plain types
    apply_overrides(data, overrides)
    kind = data.get("kind", "contact")
    return resolve_contact(data) if kind == "contact" else _owner(kind).resolve(data)


def load_scene(path, overrides=()) -> dict:
    """Read, override and validate a scene file (`resolve_scene`); errors name the file."""
    try:
        return resolve_scene(read_toml(path), overrides)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None


def study_family(scenes) -> Family | None:
    """The family of a study's cases: that of its first scene (a study sweeps one base scene)."""
    scenes = list(scenes)
    return family_of(scenes[0]) if scenes else None


def plot_kind(kind: str):
    """The function drawing a family's plot kind `kind` (spec, rows, results, column) -> path, or None."""
    return next((family.plots[kind] for family in FAMILIES if kind in family.plots), None)


def plot_kinds() -> list[str]:
    """Every family's plot kinds, for the study file's schema."""
    return [kind for family in FAMILIES for kind in family.plots]


def gatherings() -> dict[str, Gathering]:
    """Every family's reports across several studies, by name."""
    return {gathering.name: gathering for family in FAMILIES for gathering in family.gatherings}


def primary_columns(columns) -> list[str]:
    """The headline metrics of the first family whose first headline metric is among `columns`
    (a contact study's when none is)."""
    columns = list(columns)
    for metrics in [family.primary_columns for family in FAMILIES if family.primary_columns] + [CONTACT_PRIMARY]:
        if metrics[0] in columns:
            return [m for m in metrics if m in columns]
    return []
