"""The 3-D truss solver: kinematics, consistent tangent, small-motion limit, stiff sub-trusses."""
import itertools

import numpy as np
import pytest

from femcontact.families.rcc.device import Rcc, device_truss, displacement, formula_stiffness
from femcontact.physics.rotation import rotation_numpy as rotation_zyx
from femcontact.families.rcc.truss import State, Truss, angles_zyx, rotation_vector


def test_rotation_order_is_rz_ry_rx_and_angles_round_trip():
    quarter = np.pi / 2
    assert np.allclose(rotation_zyx((0, 0, quarter)) @ [1, 0, 0], [0, 1, 0])
    angles = np.array([0.3, -0.7, 1.1])
    rx, ry, rz = (rotation_zyx(a) for a in np.diag(angles))
    assert np.allclose(rotation_zyx(angles), rz @ ry @ rx, atol=1e-15)
    assert np.allclose(angles_zyx(rotation_zyx(angles)), angles, atol=1e-14)
    assert np.allclose(rotation_vector([0, 0, quarter]), rotation_zyx((0, 0, quarter)), atol=1e-15)


def test_large_rigid_rotation_leaves_members_unstressed():
    """Exact kinematics are objective: a free node dragged through 1 rad by a rotating
    triangle follows it rigidly; linear kinematics would stretch its members."""
    triangle = [(0, 0, 0), (10, 0, 0), (0, 10, 0)]
    truss = Truss(triangle + [(3, 3, 8)])
    for i in range(3):
        truss.add_member(i, 3, 100.0)
    body = truss.add_rigid_set(range(3), (0, 0, 0))
    truss.prescribe(body, translation=(1, 2, 3), angles=(1.0, 0.4, -0.6))
    state = truss.solve_exact()
    expected = np.array([1, 2, 3]) + rotation_zyx((1.0, 0.4, -0.6)) @ [3, 3, 8]
    assert np.allclose(truss.nodes[3] + state.u[3], expected, rtol=0, atol=1e-10)
    assert np.abs(truss.member_forces(state)).max() < 1e-8
    linear = truss.solve_linear()  # infinitesimal rotation: the apex leaves the rigid path
    assert np.linalg.norm(truss.nodes[3] + linear.u[3] - expected) > 1.0


def test_two_bar_truss_large_deflection_satisfies_exact_equilibrium():
    """Shallow two-bar truss, apex pushed down by P: at the computed deflection w,
    P = 2 k (l - l0) (a - w) / l with l = sqrt(s^2 + (a - w)^2); linear w = P / (2 k sin^2)."""
    span, rise, k, load = 40.0, 10.0, 50.0, 60.0
    truss = Truss([(-span, 0, 0), (span, 0, 0), (0, 0, rise)])
    truss.fix(0)
    truss.fix(1)
    truss.fix(2, dofs=(0, 1))
    truss.add_member(0, 2, k)
    truss.add_member(1, 2, k)
    truss.load(2, (0, 0, -load))
    w = -truss.solve_exact().u[2, 2]
    l0, l = np.hypot(span, rise), np.hypot(span, rise - w)
    assert 2 * k * (l0 - l) * (rise - w) / l == pytest.approx(load, rel=1e-10)
    assert w > 1.5 * load / (2 * k * (rise / l0) ** 2)  # softening: far beyond the linear answer
    assert -truss.solve_linear().u[2, 2] == pytest.approx(load / (2 * k * (rise / l0) ** 2), rel=1e-12)


def test_rigid_tangent_matches_finite_differences():
    """The consistent tangent of a rigid set's holding wrench (spin update, moments about the
    moving reference point) against central differences at a strongly deflected state."""
    truss, wrist = device_truss(Rcc(50, 50, 70, 200))
    truss.prescribe(wrist, (2.0, -1.0, 1.5), (0.1, -0.05, 0.2))
    state = truss.solve_exact()
    tangent = truss.rigid_tangent(state, wrist)
    step = 1e-6
    numeric = np.empty((6, 6))
    for j in range(6):
        columns = []
        for sign in (1, -1):
            delta = np.zeros(6)
            delta[j] = sign * step
            moved = State(state.u.copy(), [state.translations[0] + delta[:3]],
                                [rotation_vector(delta[3:]) @ state.rotations[0]])
            truss._place_rigid_sets(moved)
            columns.append(truss.holding_wrench(moved, wrist, moved.translations[0]))
        numeric[:, j] = (columns[0] - columns[1]) / (2 * step)
    assert np.allclose(tangent, numeric, rtol=1e-6, atol=1e-6 * np.abs(tangent).max())


@pytest.mark.parametrize("offset", [0.0, 10.0])
def test_linear_and_exact_agree_for_tiny_motions(offset):
    """Motions of 1e-6 (mm, rad): the geometric nonlinearity is O(1e-6 / l_o) relative."""
    device = Rcc(50, 50, 70, 200, offset)
    for dof in range(6):
        truss, wrist = device_truss(device)
        motion = np.zeros(6)
        motion[dof] = 1e-6
        truss.prescribe(wrist, motion[:3], motion[3:], about=(0, 0, 0))
        linear = truss.holding_wrench(truss.solve_linear(), wrist, (0, 0, 0), linear=True)
        exact = truss.holding_wrench(truss.solve_exact(), wrist, (0, 0, 0))
        assert np.abs(exact - linear).max() <= 1e-6 * np.abs(linear).max()


@pytest.mark.parametrize("size", [1e-6, 1e-7])
def test_linear_and_exact_agree_for_tiny_loads(size):
    """Force control with loads S e_i * size: the motions agree to O(size) relative, measured
    in energy units (each component weighted by sqrt(S_ii)); the largest term is the axial
    shortening that a tilt causes, second order (b theta)^2 / l_o, hence <= 3 size."""
    device = Rcc(50, 50, 70, 200)
    weights = np.sqrt(np.diag(formula_stiffness(device)))
    for dof in range(6):
        load = formula_stiffness(device)[:, dof] * size
        linear = displacement(device, load, model="linear")
        exact = displacement(device, load)
        assert np.abs(weights * (exact - linear)).max() <= 3 * size * np.abs(weights * linear).max()


def _plate_model(ratio):
    """The RCC with its wrist plate and peg tip as one rigid set (ratio None) or as a complete
    sub-truss of members `ratio` times stiffer than the links; a tip force and a couple."""
    device = Rcc(50, 50, 70, 200)
    base, wrist = device.links()
    truss = Truss(np.vstack([base, wrist, [(0, 0, 0)]]))
    for i in range(6):
        truss.fix(i)
        truss.add_member(i, 6 + i, device.k)
    plate = range(6, 13)
    if ratio is None:
        truss.add_rigid_set(plate, (0, 0, 0))
    else:
        for i, j in itertools.combinations(plate, 2):
            truss.add_member(i, j, ratio * device.k)
    truss.load(12, (100.0, 50.0, -200.0))
    truss.load(6, (0, 0, 30.0))
    truss.load(7, (0, 0, -30.0))
    return truss


@pytest.mark.parametrize("kinematics", ["solve_linear", "solve_exact"])
def test_stiff_plate_converges_to_rigid_body_without_losing_accuracy(kinematics):
    """The plate's own flexibility gives an error c / ratio; it must stay c / ratio (not a
    round-off floor of eps * ratio) all the way to a stiffness ratio of 1e8."""
    rigid = getattr(_plate_model(None), kinematics)().u
    ratios = [1e2, 1e4, 1e6, 1e8]
    errors = [np.abs(getattr(_plate_model(r), kinematics)().u - rigid).max() / np.abs(rigid).max()
              for r in ratios]
    c = errors[1] * ratios[1]
    assert 0.5 < c < 5.0
    for ratio, error in zip(ratios[1:], errors[1:]):
        assert error * ratio == pytest.approx(c, rel=1e-3)
