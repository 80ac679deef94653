"""The dislodging family's scene kinds: a peg-in-hole contact scene whose first two steps wedge
the peg (then pull and observe), plus a `[dislodging]` table of what one study case does from
the wedged state.

- kind "dislodging" (`pull.py`): 2-D, the thesis' pulls and their thresholds (`DISLODGING`);
- kind "dislodging_methods" (`tasks.py`): 2-D or the 3-D single-hole cylinder, every key of
  kind "dislodging" and those of `METHODS_TABLE`: the degree of wedging, other ways out (shake,
  twist, pull plus shake), pulse optimisation and the 3-D pull-out.
"""
from femcontact.config.scene import check_contact, contact_schema
from femcontact.config.schema import Field, validate
from femcontact.errors import InputError

DISLODGING = {
    "case": Field("int", 1, "thesis case number (the thesis, ch. 4: 1 = l_d 7, 1000 N*mm; 2 = l_d 8, 1500 N*mm)", min=1),
    "method": Field("str", "continuous", "'continuous' (constant pull) or 'pulse' (triangle train, one per period)",
                    choices=("continuous", "pulse")),
    "pulse_hz": Field("float", 50.0, "pulse frequency (Hz), method 'pulse'", positive=True),
    "forces": Field("floats", [], "peak pull forces (N) to run and record"),
    "thesis_forces": Field("floats", [], "thesis magnitudes (N) to run at the same fraction of each model's "
                           "threshold: F = f * quasi-static pull-out / thesis_reference"),
    "thesis_reference": Field("float", 20.2, "the thesis' continuous threshold for this case (N)", positive=True),
    "thickness": Field("float", 1.0, "model thickness (mm). The scene is per mm of thickness; with absolute loads a "
                       "thickness t is the 1-mm model with the peg's mass times t (the quasi-static wedge is "
                       "homogeneous of degree 1 in the loads), which is how it is applied", positive=True),
    "rotation": Field("str", "free", "the peg's rotation during the pull: 'free' (only the pull acts on it), "
                      "'held' at its wedged angle (a pull that also restrains the rotation, as the thesis' "
                      "thresholds suggest: docs/dislodging.md) or 'spring': restrained about its wedged angle "
                      "by a gripper of rotational stiffness `rotation_stiffness`", choices=("free", "held", "spring")),
    "rotation_stiffness": Field("float", 0.0, "the gripper's rotational stiffness about the peg's wedged angle "
                                "during the pull (N*mm/rad per mm of thickness), rotation 'spring'", min=0.0),
    "search": Field("bool", True, "bisect for the threshold force"),
    "bracket": Field("floats", [], "initial bracket [low, high] (N) of the threshold; [] = 1 and 1.05 "
                     "times the quasi-static pull-out force (widened until it brackets)"),
    "tolerance": Field("float", 0.01, "bisection stops at this bracket width (N)", positive=True),
    "rise": Field("float", 0.5, "event 'dislodged': the peg's reference point risen this much (mm), "
                  "or both contact zones open; a quasi-static pull-out state moved this much is not held",
                  positive=True),
    "frame": Field("float", 0.005, "the thesis' output frame (s), for the frame-quantised impulse", positive=True),
    "dt_max": Field("float", 5e-3, "largest time increment of the dynamic pull (s)", positive=True),
    "dt_min": Field("float", 1e-8, "smallest time increment (s)", positive=True),
    "max_rise_per_increment": Field("float", 1e-3, "an increment that lifts the peg more is halved (mm)",
                                    positive=True),
    "peeq_limit": Field("float", 1e-4, "with the effect 'plasticity': a pull is damaging when it adds more than this "
                        "equivalent plastic strain (PEEQ) to the wedged state's at some point of the body; the "
                        "search then also bisects for the least damaging pull", positive=True),
}


def check_pull(scene: dict) -> None:
    """The checks a scene of kind "dislodging" needs beyond a contact scene's (InputError naming the key)."""
    problems = []
    if scene["dim"] != 2 or scene["geometry"] != "peg_in_hole" or scene["rigid"] != "peg":
        problems.append("dim, geometry, rigid: a dislodging scene is 2-D peg_in_hole with the peg rigid")
    if "inertia" not in scene["effects"] or "friction" not in scene["effects"]:
        problems.append(f"effects = {scene['effects']}: a dislodging scene needs 'friction' and 'inertia'")
    if len(scene["steps"]) not in (2, 4):
        problems.append(f"steps: {len(scene['steps'])} given, expected 4 (wedge, release, pull, observe) "
                        "or 2 (the wedging prefix)")
    settings = scene["dislodging"]
    if (settings["rotation"] == "spring") != (settings["rotation_stiffness"] > 0):
        problems.append(f"dislodging.rotation_stiffness = {settings['rotation_stiffness']:g}: a gripper spring needs "
                        f"rotation = 'spring' and a stiffness > 0 (rotation = {settings['rotation']!r})")
    bracket = settings["bracket"]
    if bracket and (len(bracket) != 2 or not 0 <= bracket[0] < bracket[1]):
        problems.append(f"dislodging.bracket = {bracket}: expected [low, high] with 0 <= low < high")
    if problems:
        raise InputError("; ".join(problems))


METHODS = ("continuous", "pulse", "shake", "twist", "pull_shake")
SHAPES = ("triangle", "square", "haversine")

METHODS_TABLE = {
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
}


def check_methods(scene: dict) -> None:
    """The checks of a scene of kind "dislodging_methods" beyond a contact scene's (InputError naming the key)."""
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


def _table(data: dict) -> tuple[dict, dict]:
    """(the contact scene's data, its [dislodging] table) of raw dislodging scene data."""
    data = dict(data)
    table = data.pop("dislodging", {})
    if not isinstance(table, dict):
        raise InputError(f"dislodging = {table!r}: expected a table")
    return {**data, "kind": "contact"}, table


def resolve(data: dict) -> dict:
    """A resolved scene of kind "dislodging" (2-D) or "dislodging_methods" (2-D or 3-D)."""
    kind = data.get("kind")
    data, table = _table(data)
    if kind == "dislodging":
        scene = validate(data, contact_schema(2, "peg_in_hole"))
        check_contact(scene)
        scene["dislodging"] = validate(table, DISLODGING, "dislodging.")
        scene["kind"] = kind
        check_pull(scene)
        return scene
    head = validate({k: data[k] for k in ("dim",) if k in data}, {"dim": contact_schema(2, "peg_in_hole")["dim"]})
    scene = validate(data, contact_schema(head["dim"], "peg_in_hole"))
    check_contact(scene)
    scene["dislodging"] = validate(table, METHODS_TABLE, "dislodging.")
    scene["kind"] = kind
    check_methods(scene)
    return scene
