"""Labels with units of the scene keys and metrics a report shows (one place for all of them).

`label(name)` gives e.g. "depth l_d (mm)" for `peg.insertion_depth`; a step-end metric
`STEP.QUANTITY` is labelled from its quantity ("tilt (deg), end of release"), `time.PHASE`
in s, and a name not listed here is shown as is. A family's headline metrics, the default
columns of a report, are the family's own (femcontact.families, `primary_columns`).
"""
from femcontact.outputs.tables import format_value

LABELS = {
    # scene keys
    "peg.insertion_depth": "depth l_d (mm)",
    "peg.width": "peg width d (mm)",
    "peg.length": "peg length (mm)",
    "hole.width": "hole width D (mm)",
    "hole.block_width": "block width (mm)",
    "hole.depth": "block depth (mm)",
    "contact.mu": "friction mu",
    "contact.gamma": "Nitsche gamma",
    "steps.0.force": "push (Fx, Fy) (N)",
    "steps.0.moment": "couple Mz (N mm)",
    "mesh.resolution": "mesh resolution",
    "rcc.theta_l": "link tilt theta_L (deg)",
    "rcc.peg_length": "peg length L (mm)",
    "rcc.b": "base length b (mm)",
    "rcc.offset_t": "base offset T (mm)",
    "motion.translation": "test translation (mm)",
    "motion.rotation": "test rotation (rad)",
    # wedging metrics (femcontact.families.wedging)
    "wedged": "wedged (simulated)",
    "analytic_wedged": "wedged (l_crit <= l_d <= mu d)",
    "wedge_reason": "why (not) wedged",
    "residual_force_A": "residual R_A (N)",
    "residual_force_B": "residual R_B (N)",
    "residual_force_A_x": "residual R_A,x (N)",
    "residual_force_A_y": "residual R_A,y (N)",
    "residual_force_A_z": "residual R_A,z (N)",
    "residual_force_B_x": "residual R_B,x (N)",
    "residual_force_B_y": "residual R_B,y (N)",
    "residual_force_B_z": "residual R_B,z (N)",
    "residual_over_load": "R_A / load scale",
    "load_scale": "load scale (N)",
    "imbalance": "|R_A + R_B| / |R_A|",
    "angle_A_deg": "R_A off contact line (deg)",
    "angle_B_deg": "R_B off contact line (deg)",
    "tilt_initial_deg": "tilt at placement (deg)",
    "tilt_loaded_deg": "tilt under load (deg)",
    "tilt_released_deg": "tilt after release (deg)",
    "tilt_deg": "tilt (deg)",
    "stabilization_force_released": "stabilisation after release (N)",
    "elastic_energy": "elastic energy (N mm)",
    "max_von_mises": "max von Mises (MPa)",
    "yield_ratio": "max von Mises / yield",
    "clearance_ratio": "clearance ratio (D - d) / D",
    "l_crit": "l_crit (mm)",
    "l_max": "l_max = mu d (mm)",
    "depth_over_l_crit": "l_d / l_crit",
    "depth_over_l_max": "l_d / (mu d)",
    "boundary_distance": "distance to a bound / l_max",
    "near_boundary": "near a bound",
    "wall_time_s": "solver time (s)",
    # contact outputs (femcontact.outputs), also as STEP.QUANTITY
    "contact_A_force": "contact force A (N)",
    "contact_B_force": "contact force B (N)",
    "contact_top_force": "contact force (N)",
    "max_pressure": "max contact pressure (MPa)",
    "newton_iterations": "Newton iterations",
    "increments": "increments",
    "yielded": "yielded",
    "max_peeq": "max PEEQ",  # the plasticity effect's columns
    "plastic_zone": "plastic zone (mm^2 in 2-D, mm^3 in 3-D)",
    # dislodging metrics (femcontact.families.dislodging)
    "threshold_force_N": "threshold pull (N)",
    "bracket_N": "threshold bracket (N)",
    "impulse_at_threshold_Ns": "impulse at the threshold (N s)",
    "time_at_threshold_s": "time to dislodge at the threshold (s)",
    "quasi_static_pullout_N": "quasi-static pull-out (N)",
    "threshold_over_pullout": "threshold / pull-out",
    "thesis_threshold_N": "thesis' threshold (N)",
    "thesis_over_thesis_continuous": "thesis' threshold / its continuous one",
    "case": "thesis case",
    "method": "pull",
    "pulse_hz": "pulse frequency (Hz)",
    "rotation": "peg rotation in the pull",
    "thickness_mm": "thickness (mm)",
    "degree_of_wedging": "degree of wedging P / (mu (N_A + N_B))",
    "dislodging.case": "thesis case",
    "dislodging.method": "pull",
    "dislodging.pulse_hz": "pulse frequency (Hz)",
    "dislodging.thickness": "thickness (mm)",
    "dislodging.task": "task",
    "optimum_objective_impulse_Ns": "least impulse found (N s)",
    "optimum_objective_peak_force_N": "least peak pull found (N)",
    # insertion metrics (femcontact.families.insertion): FE, then the analytic tier
    "two_point_onset": "two-point onset depth (mm)",
    "analytic_two_point_onset": "two-point onset, analytic (mm)",
    "peak_force": "peak insertion force (N)",
    "analytic_peak_force": "peak insertion force, analytic (N)",
    "peak_depth": "depth at the peak (mm)",
    "analytic_peak_depth": "depth at the peak, analytic (mm)",
    "chamfer_peak_force": "chamfer peak force (N)",
    "analytic_chamfer_peak_force": "chamfer peak force, analytic (N)",
    "jammed": "jammed",
    "analytic_jams": "jams (analytic)",
    **{f"{q}_error_{phase}": f"{q[0].upper()}{q[1]} error, {phase.replace('_', '-')} (rel.)"
       for q in ("fz", "fx") for phase in ("chamfer", "edge", "one_point", "two_point")},
    "peg.offset": "lateral error (mm)",
    "peg.tilt": "tilt error (deg)",
    "support.compliance_centre": "compliance centre L_g (mm)",
    "support.model": "support",
    "materials.hole.E": "hole E (MPa)",
    "dim": "dimension",
    # rcc metrics (femcontact.families.rcc)
    "max_rel_error": "largest relative error",
    "worst_dof": "worst dof",
    "motion_ratio": "translation / link length",
    "centre_z": "compliance centre z (mm)",
    "centre_z_moved": "compliance centre z, moved (mm)",
    **{f"error_{dof}": f"relative error {dof}" for dof in ("x", "y", "z", "rx", "ry", "rz")},
    # runner columns (femcontact.study.database)
    "case_id": "case",
    "status": "status",
    "wall": "wall time (s)",
    "dofs": "dofs",
    "ranks": "ranks",
    "reason": "reason",
}

def label(name: str) -> str:
    """Axis or column label of a scene key, metric or runner column, with its unit."""
    if name in LABELS:
        return LABELS[name]
    if name.startswith("time."):
        return f"time {name[5:]} (s)"
    if name.startswith("metric."):
        return label(name[7:])
    step, _, quantity = name.rpartition(".")
    if step and quantity in LABELS and not step[0].isdigit():
        return f"{LABELS[quantity]}, end of {step}"
    return name


# Metrics stored as 0/1 that mean no/yes.
FLAGS = {"wedged", "analytic_wedged", "near_boundary", "yielded", "jammed", "analytic_jams"}


def value_label(name: str, value) -> str:
    """'hole width D = 40.05 mm' for hole.width = 40.05: a legend entry or a case description."""
    text = label(name)
    quantity, unit = text, ""
    if text.endswith(")") and " (" in text:
        quantity, unit = text[:-1].rsplit(" (", 1)
    text = format_value(value)
    return f"{quantity} = {text}" + (f" {unit}" if unit and text != "none" else "")



def cell(value, name: str = "") -> str:
    """A table cell: yes/no for flags, numbers to 4 significant digits, lists as (a, b)."""
    if name in FLAGS and value in (0, 1):
        return "yes" if value else "no"
    return format_value(value).replace("\n", " ")
