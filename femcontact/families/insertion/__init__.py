"""Compliant insertion (Whitney): a rigid peg held by a compliant support (springs, a matrix or
an RCC) driven into a chamfered hole, against the analytic tier (docs/insertion.md). Contact
scenes with the effect 'compliant_support'."""
from femcontact.families.family import Accuracy, Family
from femcontact.families.insertion import metrics, report

FAMILY = Family(
    name="insertion", doc="docs/insertion.md", claims=lambda scene: "compliant_support" in scene["effects"],
    metrics=metrics.insertion_metrics,
    plots={"insertion_history": report.write_insertion_history, "jamming_diagram": report.write_jamming_diagram,
           "wedging_window": report.write_wedging_window},
    accuracy=Accuracy("femcontact.families.insertion.metrics:accuracy_rows", ("error_peak_force", "error_two_point_onset"),
                      (("error_peak_force", "2-D insertion: in-hole peak insertion force"),
                       ("error_two_point_onset", "2-D insertion: two-point onset depth"))))
