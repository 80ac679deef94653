"""Statics of a rigid peg in two-point contact (2-D, or a 3-D peg under a load in the plane of
its lean): does a load have a static equilibrium, and how much friction does it need?

The contacts can push on the peg along their normals n (N >= 0, N) and rub along their
tangents t with |T| <= mu N (Coulomb). A load, a force F (N) at a point p (mm) plus a couple
M (N*mm, counter-clockwise), has a static equilibrium exactly when minus its wrench
(F_x, F_y, M + (p x F)_z) lies in the cone spanned by the edges n +- mu t of the contacts'
friction cones, as wrenches; non-negative least squares decides. Both bodies are rigid here:
elastic deformation moves the contacts by micrometres and is ignored, and so is a wedged
peg's preload (which can hold loads beyond this limit).

For the peg-in-hole placement of the thesis, ch. 3 (geometry.placement, 'two_point'), contact A
is the hole's mouth corner on the peg's side, pushing along the peg's inward side normal,
and contact B the peg's tip corner on the opposite wall, pushed back along -x. A 3-D peg leans
in the x-z plane: its section there is the 2-D placement (x, z as x, y), and a load in that
plane (Fx, Fz and the couple My) is the 2-D load (Fx, Fz) with the couple -My (`section_load`).

The peg starts with unloaded contacts, so the placement holds a load only if the load presses
contact B: a load that turns the peg about A away from B opens B (holding it would need a
preload, as a wedged peg has). The peg then turns about A until it stands upright against A's
wall, and from there, if that wall cannot balance the load's moment, on into the opposite lean.
`reached_friction_needed` follows the peg through these configurations. That is the rigid peg's
reasoning: an elastic peg can hold such a load in two-point contact, both contacts loaded
(docs/stability.md), so a verdict drawn from it is the rigid model's, not a proof.
"""
import numpy as np
from scipy.optimize import nnls

MU_MAX = 10.0
"""Largest friction coefficient `friction_needed` searches (more is reported as infinite)."""


def _wrench(point, force) -> np.ndarray:
    """(F_x, F_y, M about the origin) of a force (N) at a point (mm)."""
    return np.array([force[0], force[1], point[0] * force[1] - point[1] * force[0]])


def has_equilibrium(contacts, force, at, couple: float, mu: float) -> bool:
    """Whether contacts [(point, inward unit normal)] with friction mu can balance `force` (N) at
    `at` (mm) plus `couple` (N*mm)."""
    load = _wrench(at, force) + np.array([0.0, 0.0, couple])
    scale = np.abs(load).max()
    if scale == 0:
        return True
    edges = []
    for point, normal in contacts:
        normal = np.asarray(normal, dtype=float)
        tangent = np.array([-normal[1], normal[0]])
        edges += [_wrench(point, normal + mu * tangent), _wrench(point, normal - mu * tangent)]
    _, residual = nnls(np.array(edges).T, -load)
    return residual <= 1e-9 * scale


def friction_needed(contacts, force, at, couple: float) -> float:
    """The least mu for which the load has a static equilibrium (to 1e-6 relative), inf above MU_MAX."""
    if has_equilibrium(contacts, force, at, couple, 0.0):
        return 0.0
    if not has_equilibrium(contacts, force, at, couple, MU_MAX):
        return float("inf")
    low, high = 0.0, MU_MAX
    while high - low > 1e-6 * high:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if has_equilibrium(contacts, force, at, couple, middle) else (middle, high)
    return high


def presses_tip(contacts, force, at, couple: float) -> bool:
    """Whether the load (`force` (N) at `at` (mm) plus `couple` (N*mm)), turning the peg about the
    first contact (the mouth corner), drives it into the second (the tip corner): the load's moment
    about the first and the second's push have moments of opposite sign (or the load none)."""
    (pivot, _), (tip, normal) = contacts
    load = _wrench(np.asarray(at) - pivot, force)[2] + couple
    push = _wrench(np.asarray(tip) - pivot, normal)[2]
    return bool(load * push <= 0)


def reached_friction_needed(scene: dict, force, couple: float, load_point: str) -> tuple[float, str] | None:
    """The least mu with which the configuration a rigid peg reaches from the scene's two-point
    placement under `force` (N) at `load_point` and `couple` (N*mm) holds it, and that
    configuration's name (inf: none holds it at any mu); None where this model does not apply.

    - 'two-point contact': the load presses the tip corner (`presses_tip`): the placement holds it
      with `placement_friction_needed`.
    - 'upright against the wall of contact A': the tip corner opens and the peg turns about A until
      its flank lies on A's wall (contacts at the mouth corner and at the tip corner's height).
    - 'into the opposite lean': that wall cannot balance the load's moment, so the peg turns on about
      its tip until the other mouth corner meets its other flank (the placement mirrored); it holds
      the load only if the load presses its tip corner there, else the peg rocks between the
      leans and slides."""
    placed = _placement(scene, load_point)
    if placed is None:
        return None
    pose, at = placed
    lean = peg_in_hole_contacts(pose)
    if presses_tip(lean, force, at, couple):
        return friction_needed(lean, force, at, couple), "two-point contact"
    corner = pose.points["contact_A"]
    tip_height = (pose.rotation.T @ (pose.points["contact_B"] - pose.origin))[1]
    depth = scene["peg"]["insertion_depth"] - tip_height
    wall = [(corner, np.array([1.0, 0.0])), (corner - np.array([0.0, depth]), np.array([1.0, 0.0]))]
    local = pose.rotation.T @ (at - pose.origin)
    upright = corner - np.array([-scene["peg"]["width"] / 2, scene["peg"]["insertion_depth"]]) + local
    needed = friction_needed(wall, force, upright, couple)
    if needed < float("inf"):
        return needed, "upright against the wall of contact A"
    mirrored_at = pose.origin + pose.rotation @ (local * np.array([-1.0, 1.0]))
    mirrored_force = [-force[0], force[1]]
    if presses_tip(lean, mirrored_force, mirrored_at, -couple):
        return friction_needed(lean, mirrored_force, mirrored_at, -couple), "into the opposite lean"
    return float("inf"), "into the opposite lean"


def placement_friction_needed(scene: dict, force, couple: float, load_point: str) -> float | None:
    """The least mu with which a rigid peg at the scene's two-point placement holds `force` (N) at
    its named point `load_point` and `couple` (N*mm), both in the plane of its lean
    (`section_load`); None where this model does not apply (no two-point placement, a load point
    the placement does not name)."""
    placed = _placement(scene, load_point)
    if placed is None:
        return None
    pose, at = placed
    return friction_needed(peg_in_hole_contacts(pose), force, at, couple)


def section_load(dim: int, force, moment) -> tuple[list, float] | None:
    """The load (`force` N, `moment` N*mm as a scene's step gives them) in the plane of the peg's
    lean: 2-D as it is, (force, couple); 3-D ((Fx, Fz), -My), the couple counter-clockwise in
    (x, z), or None where the load leaves that plane (Fy, Mx or Mz above 1e-9 of its size)."""
    force, moment = [float(f) for f in force], [float(m) for m in moment]
    if dim == 2:
        return force or [0.0, 0.0], moment[0] if moment else 0.0
    force, moment = force or [0.0] * 3, moment or [0.0] * 3
    size = max(np.abs(force).max(), np.abs(moment).max())
    if max(abs(force[1]), abs(moment[0]), abs(moment[2])) > 1e-9 * size:
        return None
    return [force[0], force[2]], -moment[1]


def step_friction_needed(scene: dict, step: dict) -> float | None:
    """The least mu with which a rigid peg at the scene's two-point placement holds the whole load
    of `step` (a scene's step: its force at its load point and its couple); None where this model
    does not apply (`placement_friction_needed`, or a 3-D load out of the plane of the lean)."""
    load = section_load(scene["dim"], step["force"], step["moment"])
    return None if load is None else placement_friction_needed(scene, *load, step["load_point"])


def _placement(scene: dict, load_point: str):
    """(the peg's two-point pose, in 3-D its section in the x-z plane; the position (mm) of
    `load_point` on it), or None where the statics do not apply (no two-point placement, a point
    the placement does not name)."""
    from geometry.placement import Pose, peg_pose

    if scene.get("peg", {}).get("placement") != "two_point":
        return None
    pose = peg_pose(scene)
    if scene["dim"] == 3:
        plane = [0, 2]
        pose = Pose(origin=pose.origin[plane], rotation=pose.rotation[np.ix_(plane, plane)], tilt=pose.tilt,
                    points={name: point[plane] for name, point in pose.points.items()})
    return (pose, pose.points[load_point]) if load_point in pose.points else None


def peg_in_hole_contacts(pose) -> list:
    """Contacts A and B of a peg placed in two-point contact (a geometry.placement.Pose, 2-D)."""
    side_normal = pose.rotation @ np.array([1.0, 0.0])  # the peg's side at A, into the peg
    return [(pose.points["contact_A"], side_normal), (pose.points["contact_B"], np.array([-1.0, 0.0]))]
