"""Dislodging a wedged peg (docs/dislodging.md, docs/dislodging_methods.md): scenes of kind
"dislodging" (the thesis' pulls and their thresholds: `pull.py`, its report `report.py`, its rows
in `make accuracy` `accuracy.py`) and "dislodging_methods" (degree of wedging, shaking, twisting,
pulse optimisation and the 3-D pull-out: `tasks.py`, `methods.py`, `pulse_optimisation.py`,
`pullout_3d.py`, the report across its studies `methods_report.py`, the gathering
"dislodging_methods"); both kinds' schemas in `scene.py`."""
from femcontact.config.schema import describe
from femcontact.families.dislodging import methods_report, scene
from femcontact.families.family import Accuracy, Family, Gathering


def run_case(resolved: dict, case_dir, checkpoint: bool = False, restart=None) -> dict:
    """One study case of either kind, in this process (the wedged state computed once, or
    restored from the study's shared prefix)."""
    if resolved["kind"] == "dislodging":
        from femcontact.families.dislodging.pull import run_case as run
    else:
        from femcontact.families.dislodging.tasks import run_case as run
    return run(resolved, case_dir, checkpoint, restart)


def study_report(study) -> tuple[list, list[tuple]]:
    """A study of the thesis' pulls: its plots and the thresholds table (none for kind
    "dislodging_methods", whose studies `methods_report.py` gathers)."""
    if study.cases[0].scene["kind"] != "dislodging":
        return [], []
    from femcontact.families.dislodging import report as thesis_report

    written = thesis_report.report(study)
    return written, thesis_report.summary_blocks(study)


def _schema_sections() -> list[tuple[str, list[tuple], str]]:
    return [("## Dislodging scene (kind = dislodging): the `[dislodging]` table",
             describe(scene.DISLODGING, "dislodging."),
             "A 2-D peg-in-hole contact scene (the keys above) plus this table. Example: "
             "[`scenes/dislodging_2d.toml`](../scenes/dislodging_2d.toml); see [dislodging.md](dislodging.md)."),
            ("## Dislodging scene (kind = dislodging_methods): the `[dislodging]` table",
             describe(scene.METHODS_TABLE, "dislodging."),
             "A 2-D or 3-D peg-in-hole contact scene plus this table. Examples: "
             "[`scenes/dislodging_methods_2d.toml`](../scenes/dislodging_methods_2d.toml), "
             "[`scenes/dislodging_methods_3d.toml`](../scenes/dislodging_methods_3d.toml); "
             "see [dislodging_methods.md](dislodging_methods.md).")]


FAMILY = Family(
    name="dislodging", doc="docs/dislodging.md", kinds=("dislodging", "dislodging_methods"), resolve=scene.resolve,
    schema_sections=_schema_sections, run_case=run_case, prefix_omits=("dislodging",), report=study_report,
    gatherings=(Gathering("dislodging_methods", methods_report.STUDY_FILES, methods_report.write),),
    primary_columns=("threshold_force_N", "bracket_N", "impulse_at_threshold_Ns", "quasi_static_pullout_N",
                     "degree_of_wedging"),
    accuracy=Accuracy("femcontact.families.dislodging.accuracy:accuracy_rows",
                      ("error_threshold_N", "error_impulse_at_threshold_Ns", "error_impulse_fixed_Ns"),
                      (("error_threshold_N", "Dislodging case 1, 50 Hz: threshold peak force"),
                       ("error_impulse_fixed_Ns", "Dislodging case 1, 50 Hz: impulse at 1.05 x pull-out"))))
