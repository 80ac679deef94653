"""Quasi-static insertion of a rigid peg on a compliant support (Whitney, Mechanical Assemblies ch. 10).

2-D, derivations in docs/whitney.md. Frame: x lateral, z up along the hole axis. The straight
hole |x| < D/2 fills z < 0; its edges E = (+-D/2, 0) are the lower ends of a chamfer of width W
at angle a from the axis (0 <= z <= W / tan a). The peg is rigid, width d = 2r, tilt theta
(rad, counter-clockwise), axis a = (-sin theta, cos theta), normal n = (cos theta, sin theta).
The support holds the compliance centre C = tip + L_g a with a lateral spring K_x and an angular
spring K_theta and is rigid along z; at insertion depth s its rest pose has the tip centre at
(eps0, -s) and the tilt theta0. Contacts slide, friction opposing the insertion.
Units: mm, N, N*mm, rad (the CLI converts degrees).
"""
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq, minimize_scalar, root

from femcontact.errors import InputError

# Contact candidates (kind, side), side -1 = left (x < 0), +1 = right: a tip corner on the
# chamfer or on the straight wall, or the hole edge E on the peg side.
CANDIDATES = (("chamfer", -1), ("chamfer", 1), ("wall", -1), ("wall", 1), ("edge", -1), ("edge", 1))
# Active sets that can close together: a tip corner on one wall with the edge on the opposite peg
# side (two-point contact), with the edge on its own side (the peg flat along a wall: "line"), or
# the corner on the chamfer with the edge on its own side: the corner sits on the edge while the
# contact force turns from the chamfer's direction to the side's (end of the chamfer crossing).
ACTIVE_SETS = ((), (0,), (1,), (2,), (3,), (4,), (5,), (2, 5), (3, 4), (2, 4), (3, 5), (0, 4), (1, 5))


@dataclass(frozen=True)
class Insertion:
    """Peg, hole, chamfer and support of one insertion (mm, N/mm, N*mm/rad, rad)."""
    peg_diameter: float
    hole_diameter: float
    mu: float
    kx: float
    ktheta: float
    lg: float
    lateral_error: float
    angular_error: float
    chamfer_width: float
    chamfer_angle: float

    @property
    def r(self) -> float:
        return 0.5 * self.peg_diameter

    @property
    def clearance(self) -> float:
        """D - d (mm)."""
        return self.hole_diameter - self.peg_diameter

    @property
    def c(self) -> float:
        """Clearance ratio (D - d) / D."""
        return self.clearance / self.hole_diameter

    @property
    def chamfer_height(self) -> float:
        """Axial length of the chamfer, W / tan a (mm)."""
        return self.chamfer_width / math.tan(self.chamfer_angle)


OPTIONS = {"peg_diameter": "--peg-diameter", "hole_diameter": "--hole-diameter", "mu": "--mu",
           "kx": "--kx", "ktheta": "--ktheta", "lg": "--lg", "lateral_error": "--lateral-error",
           "angular_error": "--angular-error", "chamfer_width": "--chamfer-width",
           "chamfer_angle": "--chamfer-angle"}


def check(p: Insertion) -> None:
    """Raise InputError naming the option (the CLI's name) of the first bad value."""
    for name, option in OPTIONS.items():
        if not math.isfinite(getattr(p, name)):
            raise InputError(f"{option} = {getattr(p, name)}: must be finite")
    if p.peg_diameter <= 0:
        raise InputError(f"--peg-diameter = {p.peg_diameter}: must be > 0")
    if p.hole_diameter <= p.peg_diameter:
        raise InputError(f"--hole-diameter = {p.hole_diameter}: must exceed the peg diameter {p.peg_diameter}")
    if p.mu < 0:
        raise InputError(f"--mu = {p.mu}: must be >= 0")
    for name in ("kx", "ktheta"):
        if getattr(p, name) <= 0:
            raise InputError(f"{OPTIONS[name]} = {getattr(p, name)}: the support stiffness must be > 0")
    if p.chamfer_width < 0:
        raise InputError(f"--chamfer-width = {p.chamfer_width}: must be >= 0")
    if not 0 < p.chamfer_angle < math.pi / 2:
        raise InputError(f"--chamfer-angle = {math.degrees(p.chamfer_angle)}: must be in (0, 90) degrees")
    if p.mu * math.tan(p.chamfer_angle) >= 1:
        raise InputError(f"--chamfer-angle = {math.degrees(p.chamfer_angle)}: mu tan(a) >= 1, "
                         f"the chamfer locks the peg (needs a < {math.degrees(math.atan(1 / p.mu)):.4g} deg)")
    if abs(p.angular_error) >= p.chamfer_angle:
        raise InputError(f"--angular-error = {math.degrees(p.angular_error)}: the model needs |theta0| "
                         f"below the chamfer angle {math.degrees(p.chamfer_angle)} deg (the tip corner leads)")
    _, n = axes(p.angular_error)
    for side in (-1, 1):
        reach = side * p.lateral_error + p.r * n[0]
        if reach > 0.5 * p.hole_diameter + p.chamfer_width:
            raise InputError(f"--lateral-error = {p.lateral_error}: the peg misses the chamfer "
                             f"(tip corner {reach:.4g} mm from the axis, chamfer mouth "
                             f"{0.5 * p.hole_diameter + p.chamfer_width:.4g} mm)")


def axes(theta: float) -> tuple[tuple, tuple]:
    """Peg axis a (tip to support) and side normal n for the tilt theta (rad)."""
    c, s = math.cos(theta), math.sin(theta)
    return (-s, c), (c, s)


def cross(a, b) -> float:
    """z-component of the 2-D cross product a x b."""
    return a[0] * b[1] - a[1] * b[0]


def dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1]


def pose(p: Insertion, s: float, u: float, theta: float) -> tuple[tuple, tuple]:
    """Compliance centre C and tip centre P (mm) at depth s, support deflection u (mm), tilt theta."""
    a0, a = axes(p.angular_error)[0], axes(theta)[0]
    centre = (p.lateral_error + u + p.lg * a0[0], -s + p.lg * a0[1])
    return centre, (centre[0] - p.lg * a[0], centre[1] - p.lg * a[1])


def contact(p: Insertion, k: int, tip, theta: float):
    """Candidate k at the peg pose: (gap mm, contact point, force on the peg per unit normal
    force, normal on the peg, reachable). Gap < 0 is penetration; the gap is that of the full
    line (chamfer line, wall line, peg side line), `reachable` says whether the contact lies on
    its segment (corner at z >= 0 on the chamfer, z <= 0 on the wall, edge above the tip)."""
    kind, side = CANDIDATES[k]
    a, n = axes(theta)
    half = 0.5 * p.hole_diameter
    if kind == "edge":
        point = (side * half, 0.0)
        arm = (point[0] - tip[0], point[1] - tip[1])
        normal = (-side * n[0], -side * n[1])
        force = (normal[0] + p.mu * a[0], normal[1] + p.mu * a[1])
        return side * dot(arm, n) - p.r, point, force, normal, dot(arm, a) >= 0
    point = (tip[0] + side * p.r * n[0], tip[1] + side * p.r * n[1])
    if kind == "wall":  # x = side D/2 below the edge
        normal, tangent = (-side, 0.0), (0.0, 1.0)
        gap, reachable = half - side * point[0], point[1] <= 0
    else:  # chamfer line through the edge (check() keeps the corner below its top at first contact)
        ca, sa = math.cos(p.chamfer_angle), math.sin(p.chamfer_angle)
        normal, tangent = (-side * ca, sa), (side * sa, ca)
        gap = (half + point[1] * math.tan(p.chamfer_angle) - side * point[0]) * ca
        reachable = point[1] >= 0
    return gap, point, (normal[0] + p.mu * tangent[0], normal[1] + p.mu * tangent[1]), normal, reachable


@dataclass
class State:
    """Quasi-static equilibrium at one depth s (mm): support deflection u (mm), tilt theta (rad),
    active candidates and their normal forces (N); Fz insertion force (N, the support pushes the
    peg down with it), Fx lateral force and M moment about the tip of the support on the peg
    (N, N*mm); l the distance along the peg from the tip to an edge contact (mm, nan without one)."""
    s: float
    u: float
    theta: float
    active: tuple
    normal_forces: tuple
    Fz: float
    Fx: float
    M: float
    l: float
    phase: str


def _reference_stiffness(p: Insertion) -> float:
    return max(p.kx, p.ktheta / p.peg_diameter ** 2)


def _residual(p: Insertion, s: float, active: tuple, y: np.ndarray) -> np.ndarray:
    """Lateral force and moment balance about C, and the gaps of the active contacts (scaled to mm)."""
    kref = _reference_stiffness(p)
    u, theta = y[0], y[1] / p.peg_diameter
    centre, tip = pose(p, s, u, theta)
    fx, moment, gaps = -p.kx * u, -p.ktheta * (theta - p.angular_error), []
    for k, force in zip(active, y[2:] * kref):
        gap, point, f, _, _ = contact(p, k, tip, theta)
        fx += force * f[0]
        moment += force * cross((point[0] - centre[0], point[1] - centre[1]), f)
        gaps.append(gap)
    return np.array([fx / kref, moment / (kref * p.peg_diameter), *gaps])


def _state(p: Insertion, s: float, active: tuple, u: float, theta: float, forces) -> State:
    """Resultants and phase label of a solved configuration."""
    centre, tip = pose(p, s, u, theta)
    Fz, l, kinds = 0.0, math.nan, []
    for k, force in zip(active, forces):
        _, point, f, _, _ = contact(p, k, tip, theta)
        Fz += force * f[1]
        if CANDIDATES[k][0] == "edge":
            l = dot((point[0] - tip[0], point[1] - tip[1]), axes(theta)[0])
        kinds.append(CANDIDATES[k][0])
    Fx = -p.kx * u
    M = -p.ktheta * (theta - p.angular_error) + cross((centre[0] - tip[0], centre[1] - tip[1]), (Fx, -Fz))
    if len(active) == 2 and "chamfer" in kinds:
        phase = "chamfer"
    elif len(active) == 2:
        phase = "two_point" if CANDIDATES[active[0]][1] != CANDIDATES[active[1]][1] else "line"
    else:
        phase = {0: "none", 1: "chamfer" if kinds == ["chamfer"] else "one_point"}[len(active)]
    return State(s, u, theta, tuple(active), tuple(forces), Fz, Fx, M, l, phase)


def solve_set(p: Insertion, s: float, active: tuple, guess=None):
    """Equilibrium with the contacts `active` closed and sliding; (u, theta, forces) or None.
    Two closed contacts fix the pose by geometry alone (two gaps in u, theta); the balance is
    then linear in their forces. One contact is solved together with its force."""
    if not active:
        return 0.0, p.angular_error, ()
    if guess is None:
        guess = np.r_[0.0, p.angular_error * p.peg_diameter, np.full(len(active), 1e-3 * p.clearance)]
    if len(active) == 2:
        def gaps(y):
            _, tip = pose(p, s, y[0], y[1] / p.peg_diameter)
            return [contact(p, k, tip, y[1] / p.peg_diameter)[0] for k in active]
        placed = root(gaps, guess[:2], method="hybr", options={"xtol": 1e-14}).x
        base = _residual(p, s, active, np.r_[placed, 0.0, 0.0])[:2]
        balance = np.column_stack([_residual(p, s, active, np.r_[placed, unit])[:2] - base for unit in np.eye(2)])
        if not np.all(np.isfinite(balance)) or np.linalg.cond(balance) > 1e12:
            return None
        y = np.r_[placed, np.linalg.solve(balance, -base)]
    else:
        y = root(lambda y: _residual(p, s, active, y), guess, method="hybr", options={"xtol": 1e-13}).x
        if not np.all(np.isfinite(y)) or np.max(np.abs(_residual(p, s, active, y))) > 1e-10 * p.peg_diameter:
            y = root(lambda y: _residual(p, s, active, y), guess, method="lm", options={"xtol": 1e-15}).x
    if not np.all(np.isfinite(y)) or np.max(np.abs(_residual(p, s, active, y))) > 1e-10 * p.peg_diameter:
        return None
    return y[0], y[1] / p.peg_diameter, tuple(y[2:] * _reference_stiffness(p))


def feasible(p: Insertion, s: float, active: tuple, u: float, theta: float, forces) -> bool:
    """Normal forces >= 0, active contacts on their segments, no other candidate penetrating."""
    if forces and min(forces) < -1e-9 * max(abs(force) for force in forces):
        return False
    _, tip = pose(p, s, u, theta)
    for k in range(len(CANDIDATES)):
        gap, _, _, _, reachable = contact(p, k, tip, theta)
        if k in active and not reachable and abs(segment_end_offset(p, k, tip, theta)) > 1e-9 * p.peg_diameter:
            return False
        if k not in active and reachable and gap < -1e-9 * p.clearance:
            return False
    return True


def segment_end_offset(p: Insertion, k: int, tip, theta: float) -> float:
    """How far (mm) candidate k's contact lies beyond the end of its segment (the corner's height
    for chamfer and wall contacts, the edge's distance along the peg from the tip); the sign is
    irrelevant, only |value| <= round-off admits a contact at the very end."""
    _, point, _, _, _ = contact(p, k, tip, theta)
    if CANDIDATES[k][0] == "edge":
        return dot((point[0] - tip[0], point[1] - tip[1]), axes(theta)[0])
    return point[1]


def neighbours(active: tuple) -> list:
    """Active sets one step away along a sliding path: one contact closed or released, or one
    contact handed over to another candidate on the same side of the hole (a corner moving from
    the chamfer to the wall, or from the chamfer onto the edge)."""
    now = set(active)
    steps = []
    for other in ACTIVE_SETS:
        change = now ^ set(other)
        if len(change) == 1 or (len(change) == 2 and len(now & change) == 1
                                and len({CANDIDATES[k][1] for k in change}) == 1):
            steps.append(other)
    return steps


def solve_depth(p: Insertion, s: float, previous: dict | None = None, last: State | None = None) -> State | None:
    """Equilibrium at depth s. Without `last`: the admissible set with the fewest closed contacts.
    After the state `last`: its set while admissible (branches overlap, e.g. at the chamfer's
    end), else the admissible neighbouring set nearest to its pose; None when there is none: no
    sliding equilibrium continues the path, the peg jams. `previous` maps active sets to earlier
    solutions, used as starting guesses and updated."""
    previous = {} if previous is None else previous

    def admissible(active):
        solution = solve_set(p, s, active, previous.get(active))
        if solution is None or not feasible(p, s, active, *solution):
            return None
        previous[active] = np.r_[solution[0], solution[1] * p.peg_diameter,
                                 np.array(solution[2]) / _reference_stiffness(p)]
        return _state(p, s, active, *solution)

    if last is None:
        return next((state for state in map(admissible, ACTIVE_SETS) if state is not None), None)
    state = admissible(last.active)
    if state is not None:
        return state
    found = [state for state in map(admissible, neighbours(last.active)) if state is not None]
    return min(found, key=lambda st: abs(st.u - last.u) + p.peg_diameter * abs(st.theta - last.theta),
               default=None)


def start_depth(p: Insertion) -> float:
    """Depth (mm, negative: above the hole edges) at which the tip corners reach the chamfer top."""
    _, n = axes(p.angular_error)
    return -(p.chamfer_height + p.r * abs(n[1])) - 1e-3 * p.peg_diameter


def inside_friction_cones(p: Insertion, state: State) -> bool:
    """Two-point contact whose contact points lie inside each other's friction cones (the
    necessary condition for wedging): the line joining them within atan(mu) of both normals."""
    if state.phase != "two_point":
        return False
    _, tip = pose(p, state.s, state.u, state.theta)
    (_, p1, _, n1, _), (_, p2, _, n2, _) = (contact(p, k, tip, state.theta) for k in state.active)
    length = math.dist(p1, p2)
    e = ((p2[0] - p1[0]) / length, (p2[1] - p1[1]) / length)
    cos_cone = 1.0 / math.hypot(1.0, p.mu)
    return dot(e, n1) >= cos_cone and -dot(e, n2) >= cos_cone


def insertion(p: Insertion, depth_max: float, points: int = 201) -> dict:
    """Force history from the chamfer top to depth_max (mm) on `points` depths, with the
    two-point onset (refined by root finding), the peak force after the chamfer crossing and its
    depth (refined), the chamfer peak, and the wedging and jamming flags. `jams`: at some depth
    no sliding equilibrium exists (the history stops there, at `jam_depth`)."""
    check(p)
    if not (math.isfinite(depth_max) and depth_max > 0):
        raise InputError(f"--depth-max = {depth_max}: must be a finite depth > 0")
    if points < 3:
        raise InputError(f"--points = {points}: need at least 3")
    guesses, states = {}, []
    for s in np.linspace(start_depth(p), depth_max, points):
        state = solve_depth(p, float(s), guesses, states[-1] if states else None)
        if state is None:
            break
        states.append(state)
    jams = len(states) < points
    onset = _two_point_onset(p, states)
    peak = _in_hole_peak(p, states)
    chamfer = [st for st in states if st.phase == "chamfer"]
    return {
        "depth": [st.s for st in states], "Fz": [st.Fz for st in states], "Fx": [st.Fx for st in states],
        "M": [st.M for st in states], "theta": [math.degrees(st.theta) for st in states],
        "phase": [st.phase for st in states], "two_point_onset": onset,
        "peak_force": peak.Fz if peak else None, "peak_depth": peak.s if peak else None,
        "chamfer_peak_force": max(st.Fz for st in chamfer) if chamfer else None,
        "wedging_possible": any(inside_friction_cones(p, st) for st in states),
        "jams": jams, "jam_depth": (float(np.linspace(start_depth(p), depth_max, points)[len(states)])
                                    if jams else None),
        "states": states,
    }


def _two_point_onset(p: Insertion, states: list) -> float | None:
    """Depth where the one-point branch closes its second contact (gap root), else the first
    two-point depth of the grid; None without two-point contact."""
    for before, after in zip(states, states[1:]):
        if after.phase == "two_point" and before.phase != "two_point":
            if before.phase != "one_point":
                return after.s
            new = (set(after.active) - set(before.active)).pop()

            def gap(s):
                solution = solve_set(p, s, before.active)
                if solution is None:
                    raise RuntimeError(f"one-point branch lost at depth {s}")
                _, tip = pose(p, s, solution[0], solution[1])
                return contact(p, new, tip, solution[1])[0]
            if gap(before.s) * gap(after.s) > 0:  # the one-point branch ends for another reason
                return after.s
            return float(brentq(gap, before.s, after.s, xtol=1e-10))
    return None


def _in_hole_peak(p: Insertion, states: list) -> State | None:
    """Largest insertion force after the chamfer crossing (one-point, two-point or line
    contact), refined between its grid neighbours when they are in the hole too."""
    inside = [i for i, st in enumerate(states) if st.phase in ("one_point", "two_point", "line")]
    if not inside:
        return None
    i = max(inside, key=lambda j: states[j].Fz)
    if i - 1 in inside and i + 1 in inside:
        lo, hi = states[i - 1].s, states[i + 1].s
        best = minimize_scalar(lambda s: -_force_at(p, s, states[i - 1]), bounds=(lo, hi), method="bounded",
                               options={"xatol": 1e-6 * (hi - lo)})
        refined = solve_depth(p, float(best.x), last=states[i - 1])
        if refined is not None and refined.Fz > states[i].Fz:
            return refined
    return states[i]


def _force_at(p: Insertion, s: float, last: State) -> float:
    state = solve_depth(p, s, last=last)
    return state.Fz if state is not None else 0.0


# ---- closed forms (small angles, theta0 = 0, peg on the right: eps0 > (D - d)/2) -------------

def chamfer_gain(a: float, mu: float) -> float:
    """k_a = Fz / Fx on the chamfer at angle a (rad) from the axis: (tan a + mu) / (1 - mu tan a)."""
    return (math.tan(a) + mu) / (1 - mu * math.tan(a))


def chamfer_lateral_force(p: Insertion, travel: float) -> float:
    """Lateral contact force (N) after the chamfer pushed the tip `travel` mm toward the axis:
    travel / [1/K_x + L_g (L_g - r k_a) / K_theta]."""
    k_a = chamfer_gain(p.chamfer_angle, p.mu)
    return travel / (1 / p.kx + p.lg * (p.lg - p.r * k_a) / p.ktheta)


def one_point(p: Insertion, l: float) -> tuple[float, float, float]:
    """Edge on the peg side at l (mm) from the tip: normal force N (N), tilt (rad, negative:
    tip swung toward the far wall) and insertion force N (mu - theta) (N). Whitney's F_z = mu N
    drops the N |theta| of the tilted side; delta = eps0 - (D - d)/2 (the reference's c r)."""
    delta = p.lateral_error - 0.5 * p.clearance
    arm = p.lg - l - p.mu * p.r
    force = delta / (1 / p.kx + (p.lg - l) * arm / p.ktheta)
    theta = -force * arm / p.ktheta
    return force, theta, force * (p.mu - theta)


def two_point_tilt(d: float, D: float, l: float) -> float:
    """Exact 2-D tilt magnitude (rad) solving D = d cos(theta) + l sin(theta) (l along the peg)."""
    return math.atan2(l, d) - math.acos(D / math.hypot(d, l))


def two_point(p: Insertion, l: float) -> tuple[float, float, float, float]:
    """Edge contact at l (mm) along the peg and tip corner on the far wall, theta = -(D - d)/l:
    forces f1 (edge), f2 (corner) (N), insertion force mu (f1 + f2) + |theta| f1 and Whitney's
    mu (f1 + f2) (N)."""
    tilt = p.clearance / l
    lateral = p.kx * (p.lateral_error + 0.5 * p.clearance - p.lg * tilt)
    f1 = (lateral * (p.lg - p.mu * p.r) - p.ktheta * tilt) / l
    f2 = f1 - lateral
    return f1, f2, p.mu * (f1 + f2) + tilt * f1, p.mu * (f1 + f2)


def two_point_peak(p: Insertion) -> tuple[float, float]:
    """Whitney's peak of mu (f1 + f2): depth l* = 2b/a (mm) and force mu (a^2/(4b) - K_x delta') (N)."""
    delta = p.lateral_error + 0.5 * p.clearance
    a = 2 * p.kx * (p.lg - p.mu * p.r) * delta + p.kx * p.lg * p.clearance
    b = 2 * p.clearance * (p.ktheta + p.kx * p.lg * (p.lg - p.mu * p.r))
    return 2 * b / a, p.mu * (a * a / (4 * b) - p.kx * delta)


def one_point_onset(p: Insertion) -> float | None:
    """Depth (mm) where the one-point tilt reaches the two-point tilt: l |theta_1(l)| = D - d
    (first root below L_g - mu r), None if the peg never tilts that far."""
    top = p.lg - p.mu * p.r
    grid = np.linspace(1e-9, top, 2001)[:-1] if top > 0 else []
    values = [l * -one_point(p, l)[1] - p.clearance for l in grid]
    for (l0, v0), (l1, v1) in zip(zip(grid, values), zip(grid[1:], values[1:])):
        if v0 < 0 <= v1:
            return float(brentq(lambda l: l * -one_point(p, l)[1] - p.clearance, l0, l1))
    return None


def onset_stiff_angular_limit(p: Insertion) -> float:
    """Reconstructed [?] onset for K_theta >> K_x L_g^2: (D - d) K_theta / (K_x L_g eps0) (mm)."""
    return p.clearance * p.ktheta / (p.kx * p.lg * p.lateral_error)


def compliance_factor(p: Insertion) -> float:
    """S = L_g / (L_g^2 + K_theta / K_x) (1/mm)."""
    return p.lg / (p.lg ** 2 + p.ktheta / p.kx)


def wedging_tilt(c: float, mu: float) -> float:
    """theta_W = c / mu (rad): two-point tilts above it lie in the wedging range l < mu d."""
    return c / mu


def max_entry_tilt(c: float) -> float:
    """Largest tilt that still enters, exact acos(1 - c) (rad; small-angle sqrt(2c))."""
    return math.acos(1 - c)


def jamming_corners(lam: float, mu: float) -> np.ndarray:
    """Corners of the jamming parallelogram in (F_x/F_z, M/(r F_z)), lambda = l / (mu d)."""
    return np.array([[-1 / mu, 2 * lam + 1], [1 / mu, -1], [1 / mu, -(2 * lam + 1)], [-1 / mu, 1]])


def jamming_bounds(ratio_x: float, lam: float, mu: float) -> tuple[float, float]:
    """Lower and upper M/(r F_z) of the parallelogram at F_x/F_z = ratio_x (|ratio_x| <= 1/mu):
    the two-point sides M/(r F_z) = -+lambda - mu (1 + lambda) F_x/F_z."""
    return -lam - mu * (1 + lam) * ratio_x, lam - mu * (1 + lam) * ratio_x


def inside_parallelogram(ratio_x: float, ratio_m: float, lam: float, mu: float) -> bool:
    """Applied (F_x/F_z, M/(r F_z)) inside or on the parallelogram: the peg slides in; outside it jams."""
    lower, upper = jamming_bounds(ratio_x, lam, mu)
    return abs(ratio_x) <= 1 / mu and lower <= ratio_m <= upper


def draper(lg: float | None = None, lateral_error: float = 1.0, chamfer_width: float = 1.5,
           chamfer_angle: float = math.radians(45), kx: float = 7.0) -> Insertion:
    """Whitney's Draper-RCC experiment (Whitney, Mechanical Assemblies ch. 10): d 12.672, D 12.705 mm, mu 0.1,
    K_x 40 lb/in (7.0 N/mm), K_theta 53000 N*mm/rad, L_g = 4r by default, lateral error only.
    The chamfer is not in the source (our choice)."""
    d = 12.672
    return Insertion(d, 12.705, 0.1, kx, 53000.0, 2 * d if lg is None else lg, lateral_error, 0.0,
                     chamfer_width, chamfer_angle)


PHASE_COLOURS = {"chamfer": "tab:orange", "one_point": "tab:green", "two_point": "tab:red", "line": "tab:purple"}


def write_plots(p: Insertion, depth_max: float, directory, points: int = 201) -> list:
    """Write whitney_force_history.png (Fz, Fx against depth, phases shaded, for p and for the
    same support with L_g = 0) and whitney_jamming.png (parallelograms for a few lambda, with the
    applied ratios of p in one- and two-point contact) into `directory`; returns the paths."""
    from pathlib import Path

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    cases = [(f"L_g = {p.lg:.3g} mm", p), ("L_g = 0 (centre at the tip)", replace(p, lg=0.0))]
    fig, panels = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for panel, (title, case) in zip(panels, cases):
        result = insertion(case, depth_max, points)
        depth = np.array(result["depth"])
        for phase, colour in PHASE_COLOURS.items():
            mask = np.array([ph == phase for ph in result["phase"]])
            if mask.any():
                panel.fill_between(depth, 0, 1, where=mask, color=colour, alpha=0.15, step="mid",
                                   transform=panel.get_xaxis_transform(), label=phase)
        panel.plot(depth, result["Fz"], "k-", label="F_z (insertion)")
        panel.plot(depth, result["Fx"], "b--", label="F_x (support, lateral)")
        panel.set_title(title)
        panel.set_xlabel("insertion depth below the hole edge (mm)")
        panel.grid(alpha=0.3)
    panels[0].set_ylabel("force (N)")
    panels[0].set_yscale("symlog", linthresh=1.0)
    panels[0].legend(fontsize=8)
    fig.tight_layout()
    history = directory / "whitney_force_history.png"
    fig.savefig(history, dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 5))
    states = [st for st in insertion(p, depth_max, points)["states"] if st.phase in ("one_point", "two_point")]
    two_point = [st.l / (p.mu * p.peg_diameter) for st in states if st.phase == "two_point"]
    for lam in sorted({0.5, 1.0, *(round(x, 2) for x in two_point[:1] + two_point[-1:])}):
        corners = jamming_corners(lam, p.mu)
        ax.plot(*np.vstack([corners, corners[:1]]).T, label=f"lambda = {lam:g}")
    if states:
        ax.scatter([st.Fx / st.Fz for st in states], [st.M / (p.r * st.Fz) for st in states], s=8,
                   c=[PHASE_COLOURS[st.phase] for st in states], label="applied ratios (green 1-pt, red 2-pt)")
    ax.set_xlabel("F_x / F_z")
    ax.set_ylabel("M / (r F_z)")
    ax.set_title(f"Jamming diagram, mu = {p.mu:g}: inside slides, outside jams")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    jamming = directory / "whitney_jamming.png"
    fig.savefig(jamming, dpi=120)
    plt.close(fig)
    return [history, jamming]
