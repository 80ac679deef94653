"""The rigid peg's signed distance and its gradient (the contact normal), evaluated by UFL at
points, against closed forms and against central differences of the distance.

The 3-D peg is a cylinder of radius R = 20 and length L = 10 mm (local frame centred on the
peg, axis z); `peg.corner_radius` r rounds both rims into a quarter torus of tube radius r
around the circle rho = R - r, z = +-(L/2 - r); `peg.chamfer_width` cuts its tip rim into a cone.
The 2-D peg is the same outline in (x, y). The expressions are evaluated by UFL itself, so no form
is compiled (the module runs in about 15 s)."""
import math

import numpy as np
import pytest
import ufl
from ufl.algorithms.apply_derivatives import apply_derivatives

from femcontact.effects.rigid_corners import corner_points
from femcontact.physics.signed_distance import outline, signed_distance, surface

R, L = 20.0, 10.0


def shape(dim: int, r: float, tip_contact: bool = True) -> dict:
    size = {"half_width": R} if dim == 2 else {"radius": R}
    return {"shape": "rectangle" if dim == 2 else "cylinder", **size, "length": L, "corner_radius": r,
            "chamfer_width": 0.0, "chamfer_angle": 45.0, "scale": R, "tip_contact": tip_contact}


def evaluate(rigid: dict, points) -> tuple[np.ndarray, np.ndarray]:
    """(distance, gradient) of the shape at each point (mm), as the contact effect builds them."""
    dim = len(points[0])
    cell = ufl.triangle if dim == 2 else ufl.tetrahedron
    xi = ufl.variable(ufl.SpatialCoordinate(ufl.Mesh(ufl.VectorElement("Lagrange", cell, 1))))
    gap = signed_distance(rigid, xi)
    normal = apply_derivatives(ufl.diff(gap, xi))
    points = [tuple(float(c) for c in p) for p in points]
    return (np.array([gap(p) for p in points]),
            np.array([[normal[i](p) for i in range(dim)] for p in points]))


def cylinder_point(rho: float, z: float, angle: float) -> np.ndarray:
    return np.array([rho * math.cos(angle), rho * math.sin(angle), z])


def closed_form(rho: float, z: float, r: float) -> tuple[float, np.ndarray]:
    """Distance and (rho, z) normal of the rounded cylinder at a point with z >= 0, by cases."""
    c_rho, c_z = R - r, L / 2 - r  # the rim's torus centre circle
    if rho > c_rho and z > c_z:  # beside the rim, inside or outside: the torus (a sharp edge for r = 0)
        offset = np.array([rho - c_rho, z - c_z])
        return float(np.linalg.norm(offset)) - r, offset / np.linalg.norm(offset)
    if rho > c_rho or (z <= c_z and R - rho < L / 2 - z):  # the side is nearest
        return rho - R, np.array([1.0, 0.0])
    return z - L / 2, np.array([0.0, 1.0])  # the end face is nearest


# (rho, z) in the quarter z >= 0, as (region, point) for r = 1
POINTS = {
    "end face, outside": (5.0, 6.5), "end face, on it": (12.0, 5.0), "end face, inside": (10.0, 4.7),
    "side, outside": (23.0, 2.0), "side, on it": (20.0, 1.0), "side, inside": (19.8, 0.0),
    "torus, outside": (21.0, 6.0), "torus, on it": (19.0 + math.cos(0.3), 4.0 + math.sin(0.3)),
    "torus, inside": (19.3, 4.4), "torus, on its axis line": (22.0, 4.0), "above the torus": (19.0, 7.0),
}


@pytest.mark.parametrize("r", [1.0, 0.0])
def test_cylinder_distance_and_normal_by_region(r):
    """On the flat end, on the side and around the rim (a quarter torus for r = 1 mm, a sharp
    edge for r = 0), outside, on and inside the surface, at the tip (z < 0) and the top
    (z > 0) and at three angles round the axis: the closed form to 1e-12 mm, the normal
    (the distance's gradient) to 1e-12."""
    points, expected = [], []
    for rho, z in POINTS.values():
        for side in (1.0, -1.0):
            for angle in (0.0, 2.0, -2.9):
                distance, (n_rho, n_z) = closed_form(rho, z, r)
                points.append(cylinder_point(rho, side * z, angle))
                expected.append((distance, [n_rho * math.cos(angle), n_rho * math.sin(angle), side * n_z]))
    distance, normal = evaluate(shape(3, r), points)
    assert distance == pytest.approx([d for d, _ in expected], abs=1e-12)
    assert normal == pytest.approx(np.array([n for _, n in expected]), abs=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_normal_is_the_distance_gradient(dim):
    """At 60 random points of the box around the peg (its rims rounded by 1 mm), the normal
    has unit length and equals the central difference of the distance (step 1e-5 mm) to 1e-7;
    points within 1e-3 mm of the interior's ridge, where the nearest surface switches and the
    distance has a kink, are left out."""
    rigid, extent = shape(dim, 1.0), np.r_[np.full(dim - 1, R + 3.0), L / 2 + 3.0]
    points = np.random.default_rng(2).uniform(-extent, extent, size=(60, dim))
    q = np.c_[np.linalg.norm(points[:, :-1], axis=1) - (R - 1.0), abs(points[:, -1]) - (L / 2 - 1.0)]
    points = points[(q.max(axis=1) > 0) | (abs(q[:, 0] - q[:, 1]) > 1e-3)]
    step = 1e-5
    shifted = [p + s * step * e for p in points for e in np.eye(dim) for s in (1.0, -1.0)]
    distance, normal = evaluate(rigid, points)
    differences = evaluate(rigid, shifted)[0].reshape(len(points), dim, 2) @ np.array([1.0, -1.0]) / (2 * step)
    assert np.linalg.norm(normal, axis=1) == pytest.approx(1.0, abs=1e-12)
    assert normal == pytest.approx(differences, abs=1e-7)
    assert len(points) > 45


def test_normal_turns_continuously_round_the_rim():
    """On the offset surface 0.01 mm outside the rounded peg, from the side over the rim onto the
    end face (250 points, 0.05 mm apart along the side and the face and 0.5 deg round the rim): the
    distance stays 0.01 mm and the normal turns by at most the step's angle, with no jump where
    the side, the torus and the end face meet."""
    r, offset = 1.0, 0.01
    side = [(R + offset, z) for z in np.linspace(0.0, L / 2 - r, 80, endpoint=False)]
    rim = [(R - r + (r + offset) * math.cos(a), L / 2 - r + (r + offset) * math.sin(a))
           for a in np.linspace(0.0, math.pi / 2, 180, endpoint=False)]
    face = [(rho, L / 2 + offset) for rho in np.linspace(R - r, 0.0, 20)]
    points = [cylinder_point(rho, z, 0.7) for rho, z in side + rim + face]
    distance, normal = evaluate(shape(3, r), points)
    assert distance == pytest.approx(offset, abs=1e-12)
    turn = np.arccos(np.clip(np.sum(normal[1:] * normal[:-1], axis=1), -1.0, 1.0))
    assert turn.max() < math.radians(0.5) * 1.001


def test_tip_contact_false_pushes_out_through_the_side():
    """tip_contact = false: a point inside the rounded peg, within the rim radius of its tip
    face, is pushed out radially (distance rho - R, normal radial); outside, beyond the tip
    face and beside the rim, the distance is the full shape's."""
    inside = cylinder_point(10.0, -4.9, 0.4)
    outside = [cylinder_point(10.0, -5.5, 0.4), cylinder_point(19.3, 5.4, 0.4)]
    distance, normal = evaluate(shape(3, 1.0, tip_contact=False), [inside, *outside])
    assert distance[0] == pytest.approx(-10.0, abs=1e-12)
    assert normal[0] == pytest.approx([math.cos(0.4), math.sin(0.4), 0.0], abs=1e-12)
    full = evaluate(shape(3, 1.0), outside)
    assert distance[1:] == pytest.approx(full[0], abs=1e-12)
    assert normal[1:] == pytest.approx(full[1], abs=1e-12)
    assert distance[1] == pytest.approx(0.5, abs=1e-12)


CHAMFER = 2.0  # a tip chamfer 2 mm wide at 30 deg from the axis: 2 / tan 30 deg = 3.464 mm high


def chamfered(dim: int, tip_contact: bool = True) -> dict:
    return {**shape(dim, 0.0, tip_contact), "chamfer_width": CHAMFER, "chamfer_angle": 30.0}


def test_chamfered_cylinder_distance_and_normal():
    """A tip chamfer (the cone from rho = R - 2 on the tip face to rho = R, 3.464 mm up): on
    and off the cone, its two edges, the tip face and the side, at the closed form to 1e-12."""
    height, h = CHAMFER / math.tan(math.radians(30.0)), L / 2
    cone = np.array([height, -CHAMFER]) / math.hypot(CHAMFER, height)  # outward (rho, z) normal
    on_cone = np.array([R - 1.0, -h + height / 2])
    cases = [  # (rho, z), distance, (n_rho, n_z)
        (on_cone, 0.0, cone), (on_cone + 0.3 * cone, 0.3, cone), (on_cone - 0.2 * cone, -0.2, cone),
        ((R - 3.0, -h - 0.5), 0.5, (0.0, -1.0)), ((R - 3.0, -h + 0.1), -0.1, (0.0, -1.0)),
        ((R + 0.4, 0.0), 0.4, (1.0, 0.0)), ((R - 0.1, 1.0), -0.1, (1.0, 0.0)),
        ((R - CHAMFER + 0.3, -h - 0.4), 0.5, (0.6, -0.8)),  # beyond the cone's lower edge
        ((R + 0.48, -h + height - 0.14), 0.5, (0.96, -0.28)),  # beyond the cone's upper edge
        ((R + 0.6, h + 0.8), 1.0, (0.6, 0.8)),  # the sharp top edge stays sharp
    ]
    points = [cylinder_point(rho, z, 1.1) for (rho, z), _, _ in cases]
    distance, normal = evaluate(chamfered(3), points)
    assert distance == pytest.approx([d for _, d, _ in cases], abs=1e-12)
    expected = [[n_rho * math.cos(1.1), n_rho * math.sin(1.1), n_z] for _, _, (n_rho, n_z) in cases]
    assert normal == pytest.approx(np.array(expected), abs=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_chamfered_normal_is_the_distance_gradient(dim):
    """The chamfered peg's normal: unit length and the central difference of the distance
    (step 1e-5 mm) to 1e-7 at 60 random points outside it, where the distance is smooth."""
    rigid, extent = chamfered(dim), np.r_[np.full(dim - 1, R + 3.0), L / 2 + 3.0]
    points = np.random.default_rng(3).uniform(-extent, extent, size=(60, dim))
    points = points[evaluate(rigid, points)[0] > 1e-3]
    step = 1e-5
    shifted = [p + s * step * e for p in points for e in np.eye(dim) for s in (1.0, -1.0)]
    normal = evaluate(rigid, points)[1]
    differences = evaluate(rigid, shifted)[0].reshape(len(points), dim, 2) @ np.array([1.0, -1.0]) / (2 * step)
    assert np.linalg.norm(normal, axis=1) == pytest.approx(1.0, abs=1e-12)
    assert normal == pytest.approx(differences, abs=1e-7)
    assert len(points) > 15


@pytest.mark.parametrize("rigid", [shape(2, 0.0), chamfered(2)], ids=["sharp", "chamfered"])
def test_2d_corner_points_lie_on_the_outline(rigid):
    """The sharp corners the 2-D peg tracks as slave points (effects.rigid_corners) lie on its
    outline: four for the rectangle, six with a tip chamfer (its two ends on either side)."""
    corners = corner_points(rigid)
    assert len(corners) == (6 if rigid["chamfer_width"] > 0 else 4)
    assert evaluate(rigid, corners)[0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("rigid", [shape(3, 1.0), chamfered(3)], ids=["rounded", "chamfered"])
def test_pictures_lie_on_the_contact_shape(rigid):
    """The peg drawn in rigid.xdmf and the snapshots (its 2-D outline, its 3-D surface of
    revolution, 12 angles) is the shape the contact sees: every vertex at distance 0 (1e-12 mm)."""
    flat = {**rigid, "shape": "rectangle", "half_width": R}
    outline_points = outline(flat)[:, :2]
    vertices = surface(rigid, points=12)[0]
    assert evaluate(flat, outline_points)[0] == pytest.approx(0.0, abs=1e-12)
    assert evaluate(rigid, vertices)[0] == pytest.approx(0.0, abs=1e-12)


def pin(nose: str) -> dict:
    """A snap-fit pin (geometry.snap_fit): 4 mm wide, 6 mm long, a 1-mm nose at 30 deg."""
    from geometry.snap_fit import nose_profile

    outline_pieces = nose_profile({"width": 4.0, "length": 6.0, "nose": nose, "nose_angle": 30.0,
                                   "nose_length": 1.0, "nose_points": []}).pieces
    return {"shape": "pin", "pieces": outline_pieces, "length": 6.0, "scale": 6.0}


CHAMFER_HEIGHT = CHAMFER / math.tan(math.radians(30.0))
NOSE = math.radians(30.0)


@pytest.mark.parametrize("rigid, point, normal", [
    (chamfered(2), (R - 1.0, -L / 2 + CHAMFER_HEIGHT / 2),
     np.array([CHAMFER_HEIGHT, -CHAMFER]) / math.hypot(CHAMFER, CHAMFER_HEIGHT)),
    (pin("taper"), (2.0 - 0.5 * math.tan(NOSE), 0.5), np.array([math.cos(NOSE), -math.sin(NOSE)])),
    (pin("taper"), (2.0, 3.0), np.array([1.0, 0.0])),
], ids=["chamfer", "pin nose", "pin shank"])
def test_the_normal_is_a_unit_vector_up_to_a_face(rigid, point, normal):
    """On a face of the chamfered peg and of the pin, and at round-off distances either side of
    it (1e-13 to 1e-10 mm), the distance is exact to the points' round-off and the normal is the face's, a unit vector, to
    1e-12: a node resting on the face at zero gap carries a force continuous in its position
    (a distance regularised as sqrt(s^2 + tiny^2) - tiny turns its normal by up to 1 near s = 0)."""
    offsets = np.array([-1e-10, -1e-13, 0.0, 1e-13, 1e-12, 1e-10])
    points = [np.asarray(point) + s * normal for s in offsets]
    distance, gradient = evaluate(rigid, points)
    assert distance == pytest.approx(offsets, abs=1e-14)  # the points carry round-off of eps * 20 mm
    assert gradient == pytest.approx(np.tile(normal, (len(offsets), 1)), abs=1e-12)


@pytest.mark.parametrize("nose", ["convex", "concave"])
def test_the_normal_is_a_unit_vector_up_to_a_pin_arc(nose):
    """The same on the middle of a pin's arc nose: outward from the arc's centre (convex) or
    towards it (concave). Exactly on the arc (to the round-off of its points, 1e-16 mm) the
    inside test (the radius r(z)) and the arc's own distance may disagree on the side."""
    rigid = pin(nose)
    _, centre, radius, a, b = next(piece for piece in rigid["pieces"] if piece[0] == "arc")
    direction = (np.add(a, b) / 2 - centre) / np.linalg.norm(np.add(a, b) / 2 - centre)
    normal = direction if nose == "convex" else -direction
    offsets = np.array([-1e-10, -1e-13, 1e-13, 1e-10])
    points = [np.asarray(centre) + radius * direction + s * normal for s in offsets]
    distance, gradient = evaluate(rigid, points)
    assert distance == pytest.approx(offsets, abs=1e-14)
    assert gradient == pytest.approx(np.tile(normal, (len(offsets), 1)), abs=1e-12)
