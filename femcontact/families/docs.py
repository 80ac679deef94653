"""docs/scenes.md, generated from the schemas: `python -m femcontact.families.docs > docs/scenes.md`.

A test checks that the checked-in page equals `scene_page()`, so the page cannot drift
from the code.
"""
from femcontact.config.schema import DESCRIPTION, describe
from femcontact.config.scene import contact_schema
from femcontact.families import FAMILIES
from femcontact.outputs.tables import markdown_table

HEADER = """# Scene files

A scene file (TOML) describes one simulation. `kind` selects the schema: `contact` (the finite-element
contact solver; `geometry` = `peg_in_hole`, `block` or `snap_fit`) or a study family's own kind: `rcc` (the
RCC truss), `dislodging` and `dislodging_methods` (a contact scene plus a `[dislodging]` table). Every key is validated
on load and with `--set KEY=VALUE`: an unknown key, a wrong type or an out-of-range value is one clear
error naming the key, the value and what is allowed (exit code 2, no traceback).
Every number must be finite (`nan` and `inf` are refused for every key). Also refused before
anything runs (and in a study's pre-validation of every case): `steps = []`, two steps with one
name (names key the metrics), a `load_point` that names no point of the geometry (peg_in_hole:
`peg_tip`, `peg_top`, `contact_A`, `contact_B`, `reference`; block: `indenter` (the default there),
`contact`, `reference`), `solver.petsc_options` that are not linear-solver options (`ksp_*`, `pc_*`,
`mat_*`, scalar finite values) or whose `ksp_type`, `pc_type` or `pc_factor_mat_solver_type` names no
KSP, PC or factorisation package of the installed PETSc, and sizes that make the mesh too large or
too coarse (docs/geometry.md, "Mesh-size guard"). A scene file that is not UTF-8, is a directory
or is missing is one error naming the file.
Generated from the schemas (`femcontact/config/scene.py` and the study families' in `femcontact/families/`) by
`python -m femcontact.families.docs > docs/scenes.md`.
"""


def scene_page() -> str:
    peg = describe(contact_schema(2, "peg_in_hole"))
    block = [row for row in describe(contact_schema(2, "block")) if row not in peg]
    snap = [row for row in describe(contact_schema(2, "snap_fit")) if row not in peg]
    sections = [
        ("## Contact scene, geometry = peg_in_hole (2-D shown; in 3-D `hole.kind` is `single`)", peg,
         "Example: [`scenes/wedging_2d.toml`](../scenes/wedging_2d.toml) (push, then release), "
         "[`scenes/wedging_moment_2d.toml`](../scenes/wedging_moment_2d.toml) (a couple, then release)."),
        ("## Contact scene, geometry = block (keys that differ)", block,
         "Example: [`scenes/hertz.toml`](../scenes/hertz.toml)."),
        ("## Contact scene, geometry = snap_fit (keys that differ; 2-D, or 3-D with a blade pin)", snap,
         "Examples: [`scenes/snap_fit_2d.toml`](../scenes/snap_fit_2d.toml) (insert, then withdraw) and "
         "[`scenes/snap_fit_3d.toml`](../scenes/snap_fit_3d.toml) (3-D, one spring); "
         "see [snap_fit.md](snap_fit.md)."),
        *(section for family in FAMILIES if family.schema_sections for section in family.schema_sections()),
    ]
    lines = [HEADER]
    for title, rows, example in sections:
        lines += [title, "", *markdown_table(DESCRIPTION, rows), "", example, ""]
    return "\n".join(lines)


if __name__ == "__main__":
    print(scene_page(), end="")
