"""Schema of a scene of kind "dislodging_beyond" (femcontact.scenarios.dislodging_beyond):
a peg-in-hole contact scene whose first two steps wedge the peg (2-D as in kind "dislodging",
or the 3-D single-hole cylinder), plus a `[dislodging]` table: every key of kind "dislodging"
and the keys below, which say what one study case does from the wedged state."""
from femcontact.config.dislodging import DISLODGING
from femcontact.config.schema import Field
from femcontact.errors import InputError

METHODS = ("continuous", "pulse", "shake", "twist", "pull_shake")
SHAPES = ("triangle", "square", "haversine")

BEYOND = {
    **DISLODGING,
    "task": Field("str", "wedge", "'wedge': the wedged state, its quasi-static pull-out and degree of wedging; "
                  "'threshold': threshold peak of `method` by bisection; 'optimise': the pulse minimising the "
                  "impulse to dislodge; 'optimise_peak': the pulse minimising the threshold peak force; 'pullout_3d': "
                  "quasi-static pull-out along the axis of a 3-D peg and the torques about it and across it at which "
                  "it turns",
                  choices=("wedge", "threshold", "optimise", "optimise_peak", "pullout_3d")),
    "method": Field("str", "pulse", "'continuous' (constant vertical pull), 'pulse' (vertical pulse train), "
                    "'shake' (lateral pulses at the peg top, in the direction that turns the peg against the "
                    "wedging moment), 'twist' (moment pulses about the out-of-plane axis, against the wedging "
                    "moment; magnitude F = M / d, the couple of two forces F on the top corners), "
                    "'pull_shake' (constant pull `base_pull` x pull-out plus lateral pulses)", choices=METHODS),
    "shape": Field("str", "triangle", "pulse shape", choices=SHAPES),
    "duty": Field("float", 1.0, "fraction of each period the pulse lasts", positive=True, max=1.0),
    "base_pull": Field("float", 0.5, "method 'pull_shake': the constant vertical pull, a fraction of the "
                       "quasi-static pull-out force", min=0.0, max=0.99),
    "frequency_range": Field("floats", [5.0, 200.0], "task 'optimise': pulse frequencies searched (Hz)", length=2),
    "duty_range": Field("floats", [0.2, 1.0], "task 'optimise': duties searched", length=2),
    "magnitude_range": Field("floats", [1.05, 8.0], "task 'optimise': peak forces searched, in multiples of "
                             "the quasi-static pull-out force", length=2),
    "grid_hz": Field("floats", [10.0, 50.0, 200.0], "task 'optimise': frequencies of the objective grid (Hz)"),
    "grid_duty": Field("floats", [0.5, 1.0], "task 'optimise': duties of the objective grid"),
    "grid_magnitude": Field("float", 2.0, "task 'optimise': peak force of the grid, in multiples of the pull-out",
                            positive=True),
    "evaluations": Field("int", 8, "task 'optimise': Nelder-Mead evaluations per shape after the grid", min=1),
    "peak_shapes": Field("strs", list(SHAPES), "task 'optimise_peak': pulse shapes searched", choices=SHAPES),
    "peak_evaluations": Field("int", 6, "task 'optimise_peak': Nelder-Mead evaluations (each a bisection for the "
                              "threshold peak) per shape", min=3),
    "lift": Field("float", 1e-3, "quasi-static pull-out: the wedge holds while the peg lifts less than this (mm)",
                  positive=True),
}


def check(scene: dict) -> None:
    """The checks beyond a contact scene's (InputError naming the key)."""
    s, problems = scene["dislodging"], []
    three_d = scene["dim"] == 3
    if scene["geometry"] != "peg_in_hole" or scene["rigid"] != "peg":
        problems.append("geometry, rigid: a dislodging scene is peg_in_hole with the peg rigid")
    if three_d and s["task"] not in ("wedge", "pullout_3d"):
        problems.append(f"dislodging.task = {s['task']!r}: a 3-D scene (dim = 3) runs 'pullout_3d' (or 'wedge', "
                        "its wedging prefix)")
    if not three_d and s["task"] == "pullout_3d":
        problems.append("dislodging.task = 'pullout_3d': dim = 2, expected 3")
    if not three_d and ("inertia" not in scene["effects"] or "friction" not in scene["effects"]):
        problems.append(f"effects = {scene['effects']}: a 2-D dislodging scene needs 'friction' and 'inertia'")
    if "friction" not in scene["effects"]:
        problems.append(f"effects = {scene['effects']}: a wedged peg needs 'friction'")
    if len(scene["steps"]) not in (2, 4):
        problems.append(f"steps: {len(scene['steps'])} given, expected 4 (wedge, release, pull, observe) "
                        "or 2 (the wedging prefix)")
    for key in ("frequency_range", "duty_range", "magnitude_range"):
        low, high = s[key]
        if not 0 < low < high:
            problems.append(f"dislodging.{key} = {s[key]}: expected [low, high] with 0 < low < high")
    if s["duty_range"][1] > 1:
        problems.append(f"dislodging.duty_range = {s['duty_range']}: a duty is at most 1")
    if problems:
        raise InputError("; ".join(problems))

