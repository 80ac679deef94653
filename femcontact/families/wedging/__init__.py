"""Wedging: a rigid peg pushed into two-point contact in a hole, then released; wedged or not,
against the analytic condition l_crit <= l_d <= mu d (docs/wedging.md, docs/wedging_3d.md).
Contact scenes of a peg in a hole without a compliant support."""
from femcontact.families.family import Family, Gathering
from femcontact.families.wedging import metrics, plastic_map, report

FAMILY = Family(
    name="wedging", doc="docs/wedging.md",
    claims=lambda scene: scene["geometry"] == "peg_in_hole" and "compliant_support" not in scene["effects"],
    metrics=metrics.wedge_metrics, outcome_metrics=metrics.no_equilibrium_metrics,
    primary_columns=("wedged", "analytic_wedged", "residual_force_A", "tilt_released_deg", "max_von_mises"),
    plots={"wedge_map": report.write_wedge_map}, tables=report.wedge_table,
    gatherings=(Gathering("plasticity_wedging", plastic_map.STUDY_FILES, plastic_map.write),))
