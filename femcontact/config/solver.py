"""The solver's options, typed: what `SchurNewton` and `Simulation` take instead of the scene.

`solver_options(scene)` builds them once from the scene's `[solver]` table (docs/scenes.md); the
continuation settings after a failed Newton solve are not scene keys, they keep their defaults.
"""
from dataclasses import MISSING, dataclass, fields
from types import MappingProxyType


@dataclass(frozen=True)
class SolverOptions:
    """Newton's tolerances and strategies, the increment cutting and the linear solver. The
    fields without a default are the scene's `[solver]` keys (their defaults live in the schema).

    Newton stops when |R| (the rigid body's moments divided by its size, so every row is a
    force) <= atol + rtol * (the largest of the bulk, load and contact force
    norms) + the residual's round-off floor (all in N)."""
    max_iterations: int
    """Newton iterations per solve."""
    rtol: float
    """Relative residual tolerance (dimensionless)."""
    atol: float
    """Absolute residual tolerance (N)."""
    max_cuts: int
    """Times an increment may be halved after a Newton failure."""
    line_search: bool
    """Damp a step that does not lower |R| (`SchurNewton.line_search`); off: always the full step."""
    curved_step: bool
    """Before damping, retry a rejected full step along the residual's curvature."""
    contact_update: bool
    """Factor a state-independent bulk stiffness once and add the contact by a low-rank update."""
    linear: str
    """'direct', 'iterative' or 'auto' (`femcontact.solver.linear.linear_solver`)."""
    petsc_options: MappingProxyType
    """PETSc options of the linear solver, prefix-free (e.g. {"pc_type": "lu"})."""
    stabilization_factors: tuple = (1.0, 1e-1, 1e-2, 1e-4, 1e-6, 0.0)
    """Continuation of the contact stabilisation after a plain Newton failure (the spring's
    stiffness as a fraction of E * h_contact); the last, 0, solves the exact equations."""
    stabilization_tolerance: float = 1e-3
    """Largest stabilisation force kept, relative to the peak load on the rigid body (dimensionless)."""
    stall_iterations: int = 3
    """Newton iterations in a row after which a solve whose |R| barely moves (`stall_change`) stops
    (`NewtonFailure`) instead of running on to `max_iterations`."""
    stall_change: float = 1e-4
    """Change of |R| per iteration, relative to |R|, below which an iteration counts as stalled
    (dimensionless)."""
    pseudo_failures: int = 6
    """Failed pseudo steps after which pseudo-transient continuation gives up; in the last try of
    an increment, failed pseudo steps in a row (the spring stiffened pseudo_softening **
    pseudo_failures times without a converged step)."""
    pseudo_iterations: int = 1500
    """Newton iterations (failed ones included) after which pseudo-transient continuation gives up."""
    pseudo_reach: float = 64.0
    """Contact element sizes (rotations by the body's size) a rigid body may travel by
    pseudo-transient continuation in an increment that can still be cut; farther, the cut follows
    the load more closely and costs less (dimensionless)."""
    pseudo_softening: float = 4.0
    """Factor by which a converged pseudo step softens the stabilisation spring (a failed one stiffens it)."""
    pseudo_momentum: float = 0.99
    """Fraction of the last pseudo step's motion by which the spring's tie runs ahead of the body
    where the linear solves are direct (dimensionless, below 1): under a steady unbalanced load a
    pseudo step's travel grows up to 1 / (1 - pseudo_momentum) times that of the spring alone."""


SCENE_KEYS = tuple(f.name for f in fields(SolverOptions) if f.default is MISSING)
"""The `SolverOptions` a scene's `[solver]` table sets: those without a default."""


def solver_options(scene: dict) -> SolverOptions:
    """The solver options of a resolved contact scene."""
    table = scene["solver"]
    values = {key: table[key] for key in SCENE_KEYS}
    values["petsc_options"] = MappingProxyType(dict(table["petsc_options"]))
    return SolverOptions(**values)
