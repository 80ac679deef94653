"""Remote-centre-compliance (RCC) device as a 3-D truss (the thesis, ch. 5); its geometry and design
formula in femcontact.physics.rcc.

An inverted Gough-Whitehall-Stewart platform: base joints A, B, C, wrist joints
M, N, P, Q, R, S, six double-acting spring links of axial stiffness k (N/mm):
1 A-M, 2 B-N, 3 B-P, 4 C-Q, 5 C-R, 6 A-S. The wrist plate and the peg are one rigid
body. Device frame: origin at the peg tip O (the design compliance centre), z along
the peg from the wrist plate (z = -L) to the tip, base at z = -H.

Motions d = (x, y, z, rx, ry, rz) (mm, rad) of the wrist about a point (0, 0, DZ) on
the axis: x' = p + t + R (x - p), R = Rz(rz) Ry(ry) Rx(rx). Wrenches W = (Fx, Fy, Fz,
Mx, My, Mz) (N, N*mm) are the load that holds the wrist in place, moments about the
same fixed point, so W = S d for small motions (the reference's tables).

Raised base (offset T, mm): each link's base joint slides up its own link line until
it is T above the base points A, B, C, so the two links of a corner end at separate
ball joints T*cot(theta_L) apart. The link lines, hence the small-motion stiffness and
the compliance centre, are unchanged; the links are shorter (l_o - T/sin(theta_L)), so
finite motions couple more.
"""
import math

import numpy as np

from femcontact.errors import InputError
from femcontact.families.rcc.truss import Truss, skew
from femcontact.physics.rcc import Rcc, formula_stiffness

DOFS = ("x", "y", "z", "rx", "ry", "rz")
WRENCH = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
MODELS = ("exact", "approx", "linear")


def device_truss(device: Rcc) -> tuple[Truss, int]:
    """The device as a truss: fixed base joints, wrist joints one rigid set about O."""
    base, wrist = device.links()
    truss = Truss(np.vstack([base, wrist]))
    for i in range(6):
        truss.fix(i)
        truss.add_member(i, 6 + i, device.k)
    return truss, truss.add_rigid_set(range(6, 12), (0.0, 0.0, 0.0))


def shift(about_z: float) -> np.ndarray:
    """A with d_O = A d_p: motion about p = (0, 0, DZ) seen at O; wrenches move as W_p = A^T W_O."""
    a = np.eye(6)
    a[:3, 3:] = skew((0.0, 0.0, about_z))
    return a


def approx_stiffness(device: Rcc, about_z: float = 0.0) -> np.ndarray:
    """Approximation stiffness for motions and moments about (0, 0, DZ): A^T S A."""
    a = shift(about_z)
    return a.T @ formula_stiffness(device) @ a


def _six(values, names=DOFS) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    if values.shape != (6,):
        raise InputError(f"{values.tolist()}: expected 6 components {names}")
    return values


def _check_model(model: str) -> None:
    if model not in MODELS:
        raise InputError(f"model = {model!r}: expected one of {', '.join(MODELS)}")


def wrench(device: Rcc, motion, about_z: float = 0.0, model: str = "exact") -> np.ndarray:
    """Load (Fx, Fy, Fz, Mx, My, Mz) holding the wrist moved by `motion` (x, y, z mm;
    rx, ry, rz rad) about (0, 0, DZ), moments about that point. Models: 'exact' (large
    motion), 'linear' (truss, small motion), 'approx' (reference formula)."""
    motion = _six(motion)
    _check_model(model)
    if model == "approx":
        return approx_stiffness(device, about_z) @ motion
    truss, wrist = device_truss(device)
    point = (0.0, 0.0, about_z)
    truss.prescribe(wrist, motion[:3], motion[3:], about=point)
    linear = model == "linear"
    state = truss.solve_linear() if linear else truss.solve_exact(increments=1)
    return truss.holding_wrench(state, wrist, point, linear=linear)


def displacement(device: Rcc, load, about_z: float = 0.0, model: str = "exact") -> np.ndarray:
    """Motion (x, y, z, rx, ry, rz) of the point (0, 0, DZ) on the peg under a force
    (Fx, Fy, Fz, N) applied there (it moves with the peg) and a couple (Mx, My, Mz, N*mm)."""
    load = _six(load, WRENCH)
    _check_model(model)
    if model == "approx":
        return np.linalg.solve(approx_stiffness(device, about_z), load)
    truss, wrist = device_truss(device)
    point = np.array([0.0, 0.0, about_z])
    truss.rigid_sets[wrist].point = point
    truss.load_rigid_set(wrist, load[:3], load[3:])
    linear = model == "linear"
    state = truss.solve_linear() if linear else truss.solve_exact()
    t, angles = truss.rigid_motion(state, wrist, point, linear=linear)
    return np.r_[t, angles]


def compliance_centre(device: Rcc, motion=None, load=None) -> dict:
    """Compliance centre on the peg axis from the truss tangent stiffness at an operating
    point (the unloaded device, a prescribed `motion` about the tip, or a `load` at the tip).

    Returns {'z': position along the peg axis from the tip (mm; > 0 beyond the tip, away
    from the wrist),
    'coupling': the remaining lateral-translation/tilt coupling there relative to
    sqrt(K_lateral K_tilt) (0 for a true centre)}. The centre is the point p where the
    coupling blocks of A(p)^T K A(p) vanish, in the least-squares sense."""
    truss, wrist = device_truss(device)
    if motion is not None:
        motion = _six(motion)
        truss.prescribe(wrist, motion[:3], motion[3:])
    if load is not None:
        load = _six(load, WRENCH)
        truss.load_rigid_set(wrist, load[:3], load[3:])
    state = truss.solve_exact()
    rot = np.kron(np.eye(2), state.rotations[wrist])
    k = rot.T @ truss.rigid_tangent(state, wrist) @ rot  # body axes, about the moved tip
    ez = skew((0.0, 0.0, 1.0))
    k_tt = k[:3, :3]
    # coupling blocks about p = (0, 0, z): K_tr + z K_tt [e_z]x and K_rt - z [e_z]x K_tt;
    # their lateral (x, y) / tilt (rx, ry) 2x2 parts must vanish
    c0 = np.r_[k[:2, 3:5].ravel(), k[3:5, :2].ravel()]
    g = np.r_[(k_tt @ ez)[:2, :2].ravel(), (-ez @ k_tt)[:2, :2].ravel()]
    z = -float(g @ c0) / float(g @ g)
    residual = np.abs(c0 + z * g).max() / math.sqrt(abs(k[0, 0] * k[3, 3]))
    return {"z": z, "coupling": float(residual)}
