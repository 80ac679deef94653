"""Snap fit: a pin pushed past contact springs and withdrawn, jamming as an outcome, beside the
rigid-arm model; nose design (docs/snap_fit.md). Contact scenes of geometry 'snap_fit'."""
from femcontact.families.family import Accuracy, Family
from femcontact.families.snap_fit import metrics, report

FAMILY = Family(
    name="snap_fit", doc="docs/snap_fit.md", claims=lambda scene: scene["geometry"] == "snap_fit",
    metrics=metrics.snap_fit_metrics,
    plots={"force_curves": report.write_force_curves, "sweep": report.write_sweep, "jam_map": report.write_jam_map},
    tables=report.table,
    accuracy=Accuracy("femcontact.families.snap_fit.metrics:accuracy_rows",
                      ("error_peak_insertion_force", "error_insertion_force_ratio"),
                      (("error_peak_insertion_force", "Snap fit (2-D): peak insertion force"),
                       ("error_insertion_force_ratio", "Snap fit (2-D): insertion force ratio against statics"))))
