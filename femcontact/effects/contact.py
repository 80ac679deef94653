"""Physical effects as small components that add their terms to a `Problem`.

The deformable body's residual is  R_u = bulk + contact  (N), the rigid body's is
assembled from the contact vector in `femcontact.newton`. Components:

- `elasticity` (always): Hooke, or St Venant-Kirchhoff with `large_strain`;
  `plane_stress` switches the 2-D law (plane strain otherwise).
- `contact` (always): frictionless normal contact with the rigid body by Nitsche's
  method (pressure p = [p_sigma - gamma_N g]_+, gamma_N = gamma E / h) or penalty.
- `friction`: Coulomb friction by a return map: each contact node sticks to an anchor
  point of the rigid body (history, in the rigid body's frame); the tangential
  traction is -gamma_T times the distance to it, projected on the disc of radius mu p.
- `inertia`: Newmark time integration of the rigid body (and of the deformable body
  with dynamics.deformable_inertia).
- `gravity`: body force rho * g downwards (-y in 2-D, -z in 3-D), also on the rigid body.

Only the effects a scene names are called, so an unnamed effect builds no term,
no constant and no history state.
"""
import ufl
from dolfinx import fem

from femcontact import elasticity as law
from femcontact.obstacle import signed_distance


def add_elasticity(problem) -> None:
    c = problem.constants
    large = "large_strain" in problem.effects
    lmbda, mu = law.lame(c["E"], c["nu"], "plane_stress" in problem.effects)
    u, v = problem.u, problem.v
    stress = law.svk_first_piola(u, lmbda, mu) if large else law.hooke_stress(u, lmbda, mu)
    problem.stress = stress
    problem.bulk.append(ufl.inner(stress, ufl.grad(v)) * problem.dx)
    problem.energy_density = law.energy_density(u, lmbda, mu, large)
    plane = None if problem.dim == 3 else "plane_stress" if "plane_stress" in problem.effects else "plane_strain"
    problem.von_mises = law.von_mises(stress, lmbda, mu, plane)


def add_contact(problem) -> None:
    """Normal contact terms; defines problem.gap, normal, pressure and traction."""
    c, rigid = problem.constants, problem.rigid
    x = ufl.SpatialCoordinate(problem.mesh) + problem.u
    xi = ufl.variable(rigid.to_local(x, rigid.variable))
    gap = signed_distance(problem.shape, xi)
    normal_local = ufl.diff(gap, xi)
    normal = rigid.to_global_direction(normal_local, rigid.variable)
    traction_sigma = problem.stress * ufl.FacetNormal(problem.mesh)
    p_sigma = ufl.dot(traction_sigma, normal)
    gamma_n = c["gamma"] * c["E"] / ufl.CellDiameter(problem.mesh)
    trial = p_sigma - gamma_n * gap if problem.scene["contact"]["method"] == "nitsche" else -gamma_n * gap
    # [trial]_+ with the kink counted as active, so a body touching with zero force
    # already gets the contact stiffness in Newton's first iteration
    pressure = ufl.conditional(ufl.ge(trial, 0), trial, 0.0)
    problem.xi, problem.gap, problem.normal, problem.normal_local = xi, gap, normal, normal_local
    problem.traction_sigma, problem.p_sigma, problem.pressure = traction_sigma, p_sigma, pressure
    problem.traction = pressure * normal
    if problem.scene["contact"]["theta"] == 0:
        return
    # Nitsche's theta-term: -(theta/gamma_N) (p_sigma(u) - p) p_sigma(v)
    p_sigma_v = ufl.dot(ufl.derivative(problem.stress, problem.u, problem.v) * ufl.FacetNormal(problem.mesh), normal)
    problem.contact_terms.append(-c["theta"] / gamma_n * (p_sigma - pressure) * p_sigma_v)


def add_friction(problem) -> None:
    """Coulomb friction by a return map on a stick anchor (history).

    Each contact node remembers its anchor: the point of the rigid body, in the rigid
    body's frame, that it sticks to. The trial traction is -gamma_T times the tangential
    distance from the anchor (gamma_T = gamma_t E / h_contact); it is projected on the
    disc of radius mu p. After each converged increment the anchor moves so that the
    next increment starts from the converged traction (`SchurNewton.update_anchors`), so
    a load that is removed leaves the stuck state in place."""
    c, rigid = problem.constants, problem.rigid
    anchor = problem.history_function("anchor")
    problem.initialise_anchor()
    slip_local = problem.xi - anchor
    slip_local = slip_local - ufl.dot(slip_local, problem.normal_local) * problem.normal_local
    problem.gamma_t = c["gamma_t"] * c["E"] / problem.model.h_contact
    trial = -problem.gamma_t * rigid.to_global_direction(slip_local, rigid.variable)
    normal = problem.normal
    bound = c["mu"] * problem.pressure
    if problem.dim == 2:
        tangent = ufl.as_vector([-normal[1], normal[0]])
        q = ufl.dot(trial, tangent)
        tangential = ufl.max_value(ufl.min_value(q, bound), -bound) * tangent
        size = abs(q)
    else:
        size = ufl.sqrt(ufl.dot(trial, trial) + 1e-30)
        tangential = ufl.conditional(ufl.le(size, bound), trial, bound * trial / size)
    problem.stick = ufl.conditional(ufl.And(ufl.gt(problem.pressure, 0), ufl.lt(size, bound)), 1.0, 0.0)
    problem.slip = ufl.conditional(ufl.And(ufl.gt(problem.pressure, 0), ufl.ge(size, bound)), 1.0, 0.0)
    problem.traction = problem.traction + tangential


def add_inertia(problem) -> None:
    """Newmark inertia: rigid body always, deformable body if dynamics.deformable_inertia."""
    problem.rigid_inertia = True
    if not problem.scene["dynamics"]["deformable_inertia"]:
        return
    c = problem.constants
    u_old, v_old, a_old = (problem.history_function(name) for name in ("u_old", "v_old", "a_old"))
    beta, dt = c["beta"], c["dt"]
    acceleration = (problem.u - u_old - dt * v_old) / (beta * dt ** 2) - (1 / (2 * beta) - 1) * a_old
    problem.bulk.append(c["density"] * ufl.dot(acceleration, problem.v) * problem.dx)


def add_gravity(problem) -> None:
    """Weight of the deformable body; the rigid body's weight is added by the Newton solver."""
    g = [0.0] * problem.dim
    g[-1] = -1.0
    weight = problem.constants["density"] * problem.constants["g"] * ufl.as_vector(g)
    problem.bulk.append(-ufl.dot(weight, problem.v) * problem.dx)


EFFECT_COMPONENTS = {"friction": add_friction, "inertia": add_inertia, "gravity": add_gravity}
"""Optional components in the order they are added (after elasticity and contact)."""


def constants_for(scene: dict, body: str) -> dict:
    """Initial values of the form constants the active effects need (swept without recompiling)."""
    material = scene["materials"][body]
    contact = scene["contact"]
    values = {"E": material["E"], "nu": material["nu"], "gamma": contact["gamma"], "theta": contact["theta"]}
    effects = scene["effects"]
    if "friction" in effects:
        values.update(mu=contact["mu"], gamma_t=contact["gamma_t"] or contact["gamma"])
    if "inertia" in effects and scene["dynamics"]["deformable_inertia"]:
        values.update(density=material["density"], beta=scene["dynamics"]["newmark_beta"], dt=1.0)
    if "gravity" in effects:
        values.update(density=material["density"], g=scene["dynamics"]["gravity"])
    return values


def make_constants(mesh, values: dict) -> dict:
    return {name: fem.Constant(mesh, float(value)) for name, value in values.items()}
