"""Remote-centre-compliance (RCC) device as a 3-D truss (the thesis, ch. 5).

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
import time
from dataclasses import dataclass

import numpy as np

from femcontact.errors import InputError
from femcontact.config.schema import Field
from femcontact.rcc.truss import Truss, skew

DOFS = ("x", "y", "z", "rx", "ry", "rz")
WRENCH = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
LINKS = (("A", "M"), ("B", "N"), ("B", "P"), ("C", "Q"), ("C", "R"), ("A", "S"))
MODELS = ("exact", "approx", "linear")


@dataclass(frozen=True)
class Rcc:
    """Device geometry: base length b (mm), peg length L (mm), link tilt theta_L (deg),
    link stiffness k (N/mm), base-joint offset T (mm)."""
    b: float
    peg_length: float
    theta_l: float
    k: float
    offset_t: float = 0.0

    def __post_init__(self):
        for name, value in (("b", self.b), ("peg length L", self.peg_length), ("theta_L", self.theta_l),
                            ("k", self.k), ("offset T", self.offset_t)):
            if not math.isfinite(value):
                raise InputError(f"{name} = {value}: must be a finite number")
        if not 0.0 < self.theta_l < 90.0:
            raise InputError(f"theta_L = {self.theta_l} deg: must lie in (0, 90)")
        if not self.b > 0.0:
            raise InputError(f"b = {self.b} mm: must be > 0")
        if not self.k > 0.0:
            raise InputError(f"k = {self.k} N/mm: must be > 0")
        if not self.peg_length >= 0.0:
            raise InputError(f"peg length L = {self.peg_length} mm: must be >= 0")
        if not self.h > 0.0:
            raise InputError(f"peg length L = {self.peg_length} mm: must be shorter than the device height "
                             f"H = b tan(theta_L) = {self.height:.4g} mm (h = H - L = {self.h:.4g} <= 0)")
        if not 0.0 <= self.offset_t < self.h:
            raise InputError(f"offset T = {self.offset_t} mm: must lie in [0, h) with h = {self.h:.4g} mm")

    @property
    def theta(self) -> float:
        return math.radians(self.theta_l)

    @property
    def height(self) -> float:
        """H = b tan(theta_L): base plate below the tip (mm)."""
        return self.b * math.tan(self.theta)

    @property
    def h(self) -> float:
        """h = H - L: base to wrist plate (mm)."""
        return self.height - self.peg_length

    @property
    def link_length(self) -> float:
        """l_o = h / sin(theta_L) (mm), with T = 0."""
        return self.h / math.sin(self.theta)

    @property
    def raised_link_length(self) -> float:
        """Link length with the base joints raised by T: l_o - T / sin(theta_L) (mm)."""
        return self.link_length - self.offset_t / math.sin(self.theta)

    def joints(self) -> dict:
        """Joint positions (mm): A, B, C are the corners where the link lines meet."""
        b, H, L = self.b, self.height, self.peg_length
        q = self.h / math.tan(self.theta)
        r3 = math.sqrt(3.0)
        u = q * r3 / 2 - b * r3 / 3
        w = (4 * b * r3 - 3 * q * r3) / 6
        points = {"A": (-b, -b / r3, -H), "B": (b, -b / r3, -H), "C": (0, 2 * b / r3, -H),
                  "M": (-(b - q), -b / r3, -L), "N": (b - q, -b / r3, -L), "P": (b - q / 2, u, -L),
                  "Q": (q / 2, w, -L), "R": (-q / 2, w, -L), "S": (-(b - q / 2), u, -L)}
        return {name: np.array(p, dtype=float) for name, p in points.items()}

    def links(self):
        """(base ends, wrist ends), each (6, 3) in mm, links 1-6; base ends raised by T."""
        j = self.joints()
        wrist = np.array([j[w] for _, w in LINKS])
        corner = np.array([j[c] for c, _ in LINKS])
        return corner + (self.offset_t / self.h) * (wrist - corner), wrist

    def truss(self) -> tuple[Truss, int]:
        """The device as a truss: fixed base joints, wrist joints one rigid set about O."""
        base, wrist = self.links()
        truss = Truss(np.vstack([base, wrist]))
        for i in range(6):
            truss.fix(i)
            truss.add_member(i, 6 + i, self.k)
        return truss, truss.add_rigid_set(range(6, 12), (0.0, 0.0, 0.0))


def formula_stiffness(device: Rcc) -> np.ndarray:
    """Reference approximation S (6x6, diagonal) at the tip: N/mm, N*mm/rad."""
    c2, s2 = math.cos(device.theta) ** 2, math.sin(device.theta) ** 2
    k, b2 = device.k, device.b ** 2
    return np.diag([3 * k * c2, 3 * k * c2, 6 * k * s2, k * b2 * s2, k * b2 * s2, 2 * k * b2 * c2])


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
    truss, wrist = device.truss()
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
    truss, wrist = device.truss()
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
    truss, wrist = device.truss()
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


# -- scenes ---------------------------------------------------------------------------------
SCHEMA = {
    "kind": Field("str", "rcc", choices=("contact", "rcc")),
    "name": Field("str", "rcc", "scene name"),
    "rcc": {
        "b": Field("float", 50.0, "base length b (mm)", positive=True),
        "peg_length": Field("float", 50.0, "peg length L: wrist plate to tip (mm)", min=0.0),
        "theta_l": Field("float", 70.0, "link tilt theta_L from the base plate (deg), in (0, 90)",
                         check=lambda v: None if 0.0 < v < 90.0 else "must lie in (0, 90)"),
        "k": Field("float", 200.0, "axial stiffness of each link (N/mm)", positive=True),
        "offset_t": Field("float", 0.0, "base joints raised along their links by T (mm), < h", min=0.0),
    },
    "motion": {
        "translation": Field("float", 1.0, "size of the x, y, z test motions (mm)", positive=True),
        "rotation": Field("float", 0.05, "size of the rx, ry, rz test motions (rad)", positive=True, max=1.5),
        "about_z": Field("float", 0.0, "motions and moments about (0, 0, about_z): a peg longer than "
                         "designed by about_z (mm); compared with the design formula S d"),
    },
    "centre": {
        "axial_load": Field("float", 0.0, "axial force Fz on the tip (N; < 0 pushes the peg into the device) "
                            "at which the compliance centre `centre_z` is computed"),
    },
}


def device_of(scene: dict) -> Rcc:
    """The device of a resolved rcc scene."""
    r = scene["rcc"]
    return Rcc(r["b"], r["peg_length"], r["theta_l"], r["k"], r["offset_t"])


def run_case(scene: dict) -> dict:
    """The six single-dof test motions of a scene (as in the reference's tables): exact and
    design-formula wrenches and errors; the compliance centre unloaded, under the axial load
    and after the lateral test motion."""
    start = time.perf_counter()
    device = device_of(scene)
    motion = scene["motion"]
    about_z = motion["about_z"]
    design = formula_stiffness(device)
    metrics = {"device_height": device.height, "link_height": device.h, "link_length": device.link_length,
               "short_link_length": device.raised_link_length,
               "motion_ratio": motion["translation"] / device.raised_link_length}
    errors = {}
    for i, dof in enumerate(DOFS):
        d = np.zeros(6)
        d[i] = motion["translation"] if i < 3 else motion["rotation"]
        exact = wrench(device, d, about_z)
        approx = design @ d
        errors[dof] = (exact[i] - approx[i]) / approx[i]
        metrics[f"{WRENCH[i]}_{dof}"] = float(exact[i])
        metrics[f"approx_{WRENCH[i]}_{dof}"] = float(approx[i])
        metrics[f"error_{dof}"] = float(errors[dof])
        metrics[f"coupling_{dof}"] = float(np.abs(np.delete(exact / np.sqrt(np.diag(design)), i)).max()
                                           / abs(exact[i] / math.sqrt(design[i, i])))
    worst = max(errors, key=lambda dof: abs(errors[dof]))
    metrics.update(max_rel_error=float(abs(errors[worst])), worst_dof=worst)
    timings = {"motions": time.perf_counter() - start}
    start = time.perf_counter()
    for name, kwargs in (("centre_z", {"load": [0, 0, scene["centre"]["axial_load"], 0, 0, 0]}),
                         ("centre_z_moved", {"motion": [motion["translation"], 0, 0, 0, 0, 0]}),
                         ("centre_z_unloaded", {})):
        centre = compliance_centre(device, **kwargs)
        metrics[name] = centre["z"]
        metrics[name.replace("_z", "_coupling")] = centre["coupling"]
    timings["centre"] = time.perf_counter() - start
    return {"metrics": metrics, "timings": timings,
            "info": {"model": "rcc truss", "design_stiffness_diag": np.diag(design).tolist()}}
