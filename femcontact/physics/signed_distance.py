"""Analytic rigid shapes: signed distance (mm, positive outside) as UFL expressions.

Every shape is written in its own frame, centred on its reference point (the centroid
for a peg, the centre for a disc), so the rigid body's pose only maps points into that
frame. Shapes come from `geometry.model.Model.rigid`:
rectangle (2-D peg, flat punch), cylinder (3-D peg), disc (2-D cylinder indenter),
cylinder_y (3-D cylinder indenter, axis y) and hole (a rigid hole, the peg deformable).
"""
import numpy as np
import ufl

from femcontact.errors import InputError


def _box(q, radius, tiny):
    """Signed distance to a box given q = |xi| - half_sizes (rounded by `radius`).

    Written with an explicit inside/outside branch so that a point exactly on a face
    (q_i = 0) gets that face's normal as gradient; the outside part is regularised by
    `tiny` (mm) so its derivative stays finite on the edges of the branch."""
    outside = ufl.sqrt(sum(ufl.max_value(qi, 0) ** 2 for qi in q) + tiny ** 2) - tiny
    inside = q[0]
    is_outside = ufl.gt(q[0], 0)
    for qi in q[1:]:
        inside = ufl.max_value(inside, qi)
        is_outside = ufl.Or(is_outside, ufl.gt(qi, 0))
    return ufl.conditional(is_outside, outside, inside) - radius


def reference_point(rigid: dict) -> np.ndarray:
    """The shape's reference point in its local frame (tip-centred for pegs)."""
    if rigid["shape"] in ("rectangle", "cylinder"):
        point = np.zeros(len(rigid["origin"]))
        point[-1] = rigid["length"] / 2
        return point
    return np.zeros(len(rigid["origin"]))


def signed_distance(rigid: dict, xi):
    """Signed distance from the rigid shape of a point with local coordinates xi
    (relative to the reference point), as a UFL expression. Sizes may be Constants;
    `rigid["scale"]` is a float size (mm) used for regularisation."""
    shape = rigid["shape"]
    tiny = 1e-15 * 10.0 ** round(np.log10(max(rigid["scale"], 1.0)))  # a decade, so it rarely changes the form
    if shape == "rectangle":
        r = rigid["corner_radius"]
        q = [abs(xi[0]) - (rigid["half_width"] - r), abs(xi[1]) - (rigid["length"] / 2 - r)]
        return _box(q, r, tiny)
    if shape == "cylinder":
        r = rigid["corner_radius"]
        rho = ufl.sqrt(xi[0] ** 2 + xi[1] ** 2 + tiny ** 2)
        return _box([rho - (rigid["radius"] - r), abs(xi[2]) - (rigid["length"] / 2 - r)], r, tiny)
    if shape == "disc":
        return ufl.sqrt(ufl.dot(xi, xi)) - rigid["radius"]
    if shape == "cylinder_y":
        return ufl.sqrt(xi[0] ** 2 + xi[2] ** 2) - rigid["radius"]
    if shape == "hole" and len(xi) == 2:
        return _hole_2d(rigid, xi, tiny)
    raise InputError(f"rigid shape {shape!r} in {len(xi)}-D is not available")


def _hole_2d(rigid, xi, tiny):
    """Rigid hole blocks (two blocks, or a U-shaped block) as a union of boxes."""
    D2, depth, bw = rigid["half_width"], rigid["depth"], rigid["block_width"]
    boxes = [(-(D2 + bw / 2), -depth / 2, bw / 2, depth / 2), (D2 + bw / 2, -depth / 2, bw / 2, depth / 2)]
    if rigid["kind"] == "single":
        t = rigid["bottom_thickness"]
        boxes.append((0.0, -depth - t / 2, D2 + bw, t / 2))
    distance = None
    for cx, cy, hx, hy in boxes:
        d = _box([abs(xi[0] - cx) - hx, abs(xi[1] - cy) - hy], 0.0, tiny)
        distance = d if distance is None else ufl.min_value(distance, d)
    return distance


def outline(rigid: dict, points: int = 64) -> np.ndarray:
    """Closed polyline (P x 3, local frame about the reference point) of a 2-D shape, for pictures."""
    shape = rigid["shape"]
    if shape == "rectangle":
        w, h = rigid["half_width"], rigid["length"] / 2
        xy = np.array([[-w, -h], [w, -h], [w, h], [-w, h], [-w, -h]])
    elif shape == "disc":
        t = np.linspace(0, 2 * np.pi, points)
        xy = rigid["radius"] * np.c_[np.cos(t), np.sin(t)]
    else:
        return np.zeros((0, 3))
    return np.c_[xy, np.zeros(len(xy))]
