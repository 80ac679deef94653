"""Statics of a rigid peg in two-point contact (2-D): does a load have a static equilibrium,
and how much friction does it need?

The contacts can push on the peg along their normals n (N >= 0, N) and rub along their
tangents t with |T| <= mu N (Coulomb). A load, a force F (N) at a point p (mm) plus a couple
M (N*mm, counter-clockwise), has a static equilibrium exactly when minus its wrench
(F_x, F_y, M + (p x F)_z) lies in the cone spanned by the edges n +- mu t of the contacts'
friction cones, as wrenches; non-negative least squares decides. Both bodies are rigid here:
elastic deformation moves the contacts by micrometres and is ignored, and so is a wedged
peg's preload (which can hold loads beyond this limit).

For the peg-in-hole placement of the thesis, ch. 3 (geometry.placement, 'two_point'), contact A
is the hole's mouth corner on the peg's side, pushing along the peg's inward side normal,
and contact B the peg's tip corner on the opposite wall, pushed back along -x.
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


def placement_friction_needed(scene: dict, force, couple: float, load_point: str) -> float | None:
    """The least mu with which a rigid peg at the scene's two-point placement holds `force` (N) at
    its named point `load_point` and `couple` (N*mm); None where this model does not apply (not
    2-D, no two-point placement, a load point the placement does not name)."""
    from geometry.placement import peg_pose

    if scene.get("dim") != 2 or scene.get("peg", {}).get("placement") != "two_point":
        return None
    pose = peg_pose(scene)
    if load_point not in pose.points:
        return None
    return friction_needed(peg_in_hole_contacts(pose), force, pose.points[load_point], couple)


def peg_in_hole_contacts(pose) -> list:
    """Contacts A and B of a peg placed in two-point contact (a geometry.placement.Pose, 2-D)."""
    side_normal = pose.rotation @ np.array([1.0, 0.0])  # the peg's side at A, into the peg
    return [(pose.points["contact_A"], side_normal), (pose.points["contact_B"], np.array([-1.0, 0.0]))]
