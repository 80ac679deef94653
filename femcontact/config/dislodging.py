"""Schema of a dislodging scene (kind "dislodging", femcontact.scenarios.dislodging): a 2-D
peg-in-hole contact scene whose first two steps wedge the peg, then pull and observe, plus
the `[dislodging]` table of what one study case does from the wedged state."""
from femcontact.config.schema import Field
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
    "rotation": Field("str", "free", "the peg's rotation during the pull: 'free' (only the pull acts on it) or "
                      "'held' at its wedged angle (a pull that also restrains the rotation, as the thesis' "
                      "thresholds suggest: docs/dislodging.md)", choices=("free", "held")),
    "search": Field("bool", True, "bisect for the threshold force"),
    "bracket": Field("floats", [], "initial bracket [low, high] (N) of the threshold; [] = 1 and 1.05 "
                     "times the quasi-static pull-out force (widened until it brackets)"),
    "tolerance": Field("float", 0.01, "bisection stops at this bracket width (N)", positive=True),
    "rise": Field("float", 0.5, "event 'dislodged': the peg's reference point risen this much (mm), "
                  "or both contact zones open", positive=True),
    "frame": Field("float", 0.005, "the thesis' output frame (s), for the frame-quantised impulse", positive=True),
    "dt_max": Field("float", 5e-3, "largest time increment of the dynamic pull (s)", positive=True),
    "dt_min": Field("float", 1e-8, "smallest time increment (s)", positive=True),
    "max_rise_per_increment": Field("float", 1e-3, "an increment that lifts the peg more is halved (mm)",
                                    positive=True),
}


def check(scene: dict) -> None:
    """The checks a dislodging scene needs beyond a contact scene's (InputError naming the key)."""
    problems = []
    if scene["dim"] != 2 or scene["geometry"] != "peg_in_hole" or scene["rigid"] != "peg":
        problems.append("dim, geometry, rigid: a dislodging scene is 2-D peg_in_hole with the peg rigid")
    if "inertia" not in scene["effects"] or "friction" not in scene["effects"]:
        problems.append(f"effects = {scene['effects']}: a dislodging scene needs 'friction' and 'inertia'")
    if len(scene["steps"]) not in (2, 4):
        problems.append(f"steps: {len(scene['steps'])} given, expected 4 (wedge, release, pull, observe) "
                        "or 2 (the wedging prefix)")
    bracket = scene["dislodging"]["bracket"]
    if bracket and (len(bracket) != 2 or not 0 <= bracket[0] < bracket[1]):
        problems.append(f"dislodging.bracket = {bracket}: expected [low, high] with 0 <= low < high")
    if problems:
        raise InputError("; ".join(problems))
