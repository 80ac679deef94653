"""What a simulation's solver does, recorded for tests that check which way it took."""
from femcontact.config.solver import SolverOptions

EVERY_STABILIZATION_FACTOR = list(SolverOptions.__dataclass_fields__["stabilization_factors"].default)
"""The default continuation of the contact stabilisation, every factor in turn."""


def stabilization_factors_taken(simulation) -> list:
    """The stabilisation factors `simulation`'s solver is switched to from now on (a live list)."""
    factors, stabilize = [], simulation.newton.stabilize

    def recorded(factor, tie_pose=None):
        factors.append(factor)
        stabilize(factor, tie_pose)

    simulation.newton.stabilize = recorded
    return factors
