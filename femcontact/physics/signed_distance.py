"""Analytic rigid shapes: signed distance (mm, positive outside) as UFL expressions.

Every shape is written in its own frame, centred on its reference point (the centroid
for a peg, the centre for a disc), so the rigid body's pose only maps points into that
frame. Shapes come from `geometry.model.Model.rigid`:
rectangle (2-D peg, flat punch) and cylinder (3-D peg, flat punch), a peg's corners or rims
rounded by `corner_radius` (quarter circles, quarter tori) or its tip cut by a chamfer
(`chamfer_width`, `chamfer_angle`), disc (2-D cylinder indenter),
cylinder_y (3-D cylinder indenter, axis y), sphere (3-D sphere indenter), hole (a rigid hole, the peg deformable) and
pin (snap-fit pin: a shank with a nose of segments and circular arcs, tip-centred; in 3-D a blade,
its section swept along z).
"""
import numpy as np
import ufl

from femcontact.errors import InputError


def _box(q, radius, tiny, sides_only=False):
    """Signed distance to a box (a rectangle, or a cylinder in (rho, z)) given the two
    q = |xi| - half_sizes (rounded by `radius`).

    Written with explicit branches so that the gradient (the contact normal) is a unit vector
    everywhere: inside, the nearer face (a point exactly on a face, q_i = 0, gets that face's
    normal); outside a face (one q_i > 0), the distance to that face; outside an edge (both
    q_i > 0), the distance to it, sqrt(q_0^2 + q_1^2), with `tiny` (mm) under the root only so
    its derivative stays finite in the branches not taken. `sides_only`: a point inside is
    pushed out through the side (q[0]) whatever the nearer face, so the end faces take no
    contact from inside (a peg's tip face, see `tip_contact`), also within `radius` of them."""
    q0, q1 = q
    edge = ufl.sqrt(ufl.max_value(q0, 0) ** 2 + ufl.max_value(q1, 0) ** 2 + tiny ** 2)
    outside = ufl.conditional(ufl.And(ufl.gt(q0, 0), ufl.gt(q1, 0)), edge, ufl.max_value(q0, q1))
    inside = q0 if sides_only else ufl.max_value(q0, q1)
    is_outside = ufl.Or(ufl.gt(q0, 0), ufl.gt(q1, radius if sides_only else 0))
    return ufl.conditional(is_outside, outside, inside) - radius


def _to_point(p, a, tiny):
    """Distance (mm) from the point p to the point a, in a plane, with `tiny` (mm) under the root
    only so its derivative stays finite where p = a."""
    return ufl.sqrt((p[0] - a[0]) ** 2 + (p[1] - a[1]) ** 2 + tiny ** 2)


def _away(s):
    """|s| for a signed distance s positive outside, with s's own gradient (the outward
    normal) on the surface, s = 0 (UFL's max_value takes its second operand's derivative at a tie)."""
    return ufl.max_value(-s, s)


def _to_segment(p, a, b, tiny, outward=None):
    """Distance (mm) from the point p to the segment a-b of an outline traversed counter-clockwise
    (the solid on its left): beside the segment the distance to its line, whose gradient is the
    segment's outward normal, also on it; beyond its ends the distance to the nearer end.
    `outward`: the signed distance to the segment's line (positive outside), where the caller
    has it (computed here for a segment of numbers)."""
    ex, ez = b[0] - a[0], b[1] - a[1]
    along = ((p[0] - a[0]) * ex + (p[1] - a[1]) * ez) / (ex * ex + ez * ez)
    if outward is None:
        outward = ((p[0] - a[0]) * ez - (p[1] - a[1]) * ex) / float(np.hypot(ex, ez))
    beyond = ufl.conditional(ufl.le(along, 0.0), _to_point(p, a, tiny), _to_point(p, b, tiny))
    return ufl.conditional(ufl.And(ufl.gt(along, 0.0), ufl.lt(along, 1.0)), _away(outward), beyond)


def _chamfered(rigid, half, across, along, tiny, sides_only):
    """Signed distance to a peg (half width or radius `half`, centred, axis along) whose tip
    edge is cut by a chamfer of `chamfer_width` at `chamfer_angle` (deg) from the axis: the convex
    outline tip face, chamfer, side, top face in (across, along). Inside, the largest distance
    to the four faces' lines (each face's normal as gradient, also on the face); outside, the
    distance to the nearest face. `sides_only`: inside, only the side and the chamfer count."""
    width = rigid["chamfer_width"]
    height = width / np.tan(np.radians(rigid["chamfer_angle"]))
    h = rigid["length"] / 2
    corners = [(0.0, -h), (half - width, -h), (half, height - h), (half, h), (0.0, h)]
    slant = np.hypot(width, height)
    lines = {"tip": -along - h, "chamfer": ((across - half + width) * height - (along + h) * width) / slant,
             "side": across - half, "top": along - h}
    outside_distances = [_to_segment((across, along), a, b, tiny, lines[name])
                         for a, b, name in zip(corners[:-1], corners[1:], ("tip", "chamfer", "side", "top"))]
    is_outside = ufl.gt(lines["tip"], 0)
    for name in ("chamfer", "side", "top"):
        is_outside = ufl.Or(is_outside, ufl.gt(lines[name], 0))
    faces = ("chamfer", "side") if sides_only else ("tip", "chamfer", "side", "top")
    inside, outside = lines[faces[0]], outside_distances[0]
    for name in faces[1:]:
        inside = ufl.max_value(inside, lines[name])
    for distance in outside_distances[1:]:
        outside = ufl.min_value(outside, distance)
    return ufl.conditional(is_outside, outside, inside)


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
    if shape in ("rectangle", "cylinder"):  # a peg: across its axis |x| (2-D) or rho (3-D), along it z
        half, r = rigid["half_width" if shape == "rectangle" else "radius"], rigid["corner_radius"]
        across = abs(xi[0]) if shape == "rectangle" else ufl.sqrt(xi[0] ** 2 + xi[1] ** 2 + tiny ** 2)
        along, sides_only = xi[len(xi) - 1], not rigid.get("tip_contact", True)
        if rigid.get("chamfer_width", 0.0) > 0:
            return _chamfered(rigid, half, across, along, tiny, sides_only)
        return _box([across - (half - r), abs(along) - (rigid["length"] / 2 - r)], r, tiny, sides_only)
    if shape in ("disc", "sphere"):
        return ufl.sqrt(ufl.dot(xi, xi)) - rigid["radius"]
    if shape == "cylinder_y":
        return ufl.sqrt(xi[0] ** 2 + xi[2] ** 2) - rigid["radius"]
    if shape == "hole" and len(xi) == 2:
        return _hole_2d(rigid, xi, tiny)
    if shape == "pin":  # 3-D: a blade, the same section in every plane z = const
        return _pin_2d(rigid["pieces"], rigid["length"], xi, tiny)
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


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def _pin_2d(pieces, pin_length, xi, tiny):
    """Exact signed distance of a pin symmetric about its axis, given the right half of its
    outline in (r, z) = (|x|, y) as straight segments and circular arcs (geometry.snap_fit):
    the distance is the smallest to any piece, negative inside |x| < r(y), 0 < y < length."""
    p = [abs(xi[0]), xi[1]]
    distances, radius = [], None
    for piece in pieces:
        a, b = np.asarray(piece[-2], float), np.asarray(piece[-1], float)
        if piece[0] == "segment":
            ab = b - a
            distances.append(_to_segment(p, a, b, tiny))
            r_of_z = a[0] + (xi[1] - a[1]) * ab[0] / ab[1] if ab[1] > 0 else None
        else:
            centre, R = np.asarray(piece[1], float), piece[2]
            q = [p[0] - centre[0], p[1] - centre[1]]
            first, last = (a - centre, b - centre) if _cross(a - centre, b - centre) > 0 else (b - centre, a - centre)
            in_wedge = ufl.And(ufl.ge(_cross(first, q), 0), ufl.ge(_cross(q, last), 0))
            side = 1.0 if centre[0] < b[0] else -1.0  # convex: the centre is inside the pin
            to_arc = _away(side * (ufl.sqrt(q[0] ** 2 + q[1] ** 2) - R))  # side * (...): positive outside
            to_ends = ufl.min_value(_to_point(p, a, tiny), _to_point(p, b, tiny))
            distances.append(ufl.conditional(in_wedge, to_arc, to_ends))
            r_of_z = centre[0] + side * ufl.sqrt(ufl.max_value(R * R - (xi[1] - centre[1]) ** 2, 0.0))
        if r_of_z is not None and b[1] > a[1]:
            radius = r_of_z if radius is None else ufl.conditional(ufl.le(xi[1], a[1]), radius, r_of_z)
    distance = distances[0]
    for d in distances[1:]:
        distance = ufl.min_value(distance, d)
    inside = ufl.And(ufl.And(ufl.gt(xi[1], 0), ufl.lt(xi[1], pin_length)), ufl.lt(p[0], radius))
    return ufl.conditional(inside, -distance, distance)


def _peg_profile(rigid: dict) -> np.ndarray:
    """Half outline (across, along) of a peg about its centre, from the tip centre to the top
    centre, with its rounded corners (sampled) or its tip chamfer."""
    from geometry.placement import peg_profile

    half = rigid["half_width"] if rigid["shape"] == "rectangle" else rigid["radius"]
    peg = {"width": 2 * half, **{key: rigid[key] for key in ("length", "corner_radius", "chamfer_width", "chamfer_angle")}}
    return peg_profile(peg) - [0.0, rigid["length"] / 2]


def _revolved(profile: np.ndarray, points: int) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of the surface swept by a half outline (across, along) from pole to
    pole round the axis along z, in `points` angles."""
    angle = np.linspace(0, 2 * np.pi, points, endpoint=False)
    rings = profile[1:-1]
    vertices = np.vstack([np.c_[rho * np.cos(angle), rho * np.sin(angle), np.full(points, z)] for rho, z in rings]
                         + [[[0.0, 0.0, profile[0, 1]], [0.0, 0.0, profile[-1, 1]]]])
    k, k1 = np.arange(points), (np.arange(points) + 1) % points
    bands = [np.vstack([np.c_[a + k, a + k1, a + points + k], np.c_[a + k1, a + points + k1, a + points + k]])
             for a in range(0, (len(rings) - 1) * points, points)]
    tip, top, last = len(rings) * points, len(rings) * points + 1, (len(rings) - 1) * points
    caps = [np.c_[np.full(points, tip), k1, k], np.c_[np.full(points, top), last + k, last + k1]]
    return vertices, np.vstack(bands + caps)


def outline(rigid: dict, points: int = 64) -> np.ndarray:
    """Closed polyline (P x 3, local frame about the reference point) of a 2-D shape, for pictures."""
    shape = rigid["shape"]
    if shape == "rectangle":
        right = _peg_profile(rigid)[1:-1]
        left = right[::-1] * [-1.0, 1.0]
        xy = np.vstack([right, left, right[:1]])
    elif shape == "disc":
        t = np.linspace(0, 2 * np.pi, points)
        xy = rigid["radius"] * np.c_[np.cos(t), np.sin(t)]
    elif shape == "pin":
        from geometry.snap_fit import outline as pin_outline

        xy = pin_outline(rigid["pieces"])
    else:
        return np.zeros((0, 3))
    return np.c_[xy, np.zeros(len(xy))]


def surface(rigid: dict, points: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """Triangulated surface (vertices P x 3 in the local frame about the reference point, triangles
    T x 3) of a 3-D shape, for pictures: a peg or flat punch with its end caps (rims rounded or
    chamfered as the shape is), the indenter's cylinder (axis y, 4 radii long), the snap-fit pin's
    section swept over z = +-half_width; empty for others."""
    shape = rigid["shape"]
    if shape == "cylinder":
        return _revolved(_peg_profile(rigid), points)
    if shape == "cylinder_y":  # local axis y: (x, y, z) <- (x, z_cylinder, y_cylinder)
        radius = rigid["radius"]
        vertices, triangles = _revolved(np.array([[0.0, -2 * radius], [radius, -2 * radius], [radius, 2 * radius],
                                                  [0.0, 2 * radius]]), points)
        return vertices[:, [0, 2, 1]], triangles
    if shape == "pin":
        from geometry.snap_fit import outline as pin_outline

        section = pin_outline(rigid["pieces"])
        n, half = len(section), rigid["half_width"]
        vertices = np.vstack([np.c_[section, np.full(n, -half)], np.c_[section, np.full(n, half)]])
        k = np.arange(n - 1)
        return vertices, np.vstack([np.c_[k, k + 1, n + k], np.c_[k + 1, n + k + 1, n + k]])
    return np.zeros((0, 3)), np.zeros((0, 3), dtype=int)
