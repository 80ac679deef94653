"""Newmark time integration (average acceleration by default: beta = 1/4, gamma = 1/2).

Works alike on numpy arrays (the rigid body's pose) and UFL expressions (the
deformable body's displacement): x is the displacement at the end of the increment.
"""


def acceleration(x, x_old, v_old, a_old, dt: float, beta: float):
    """Acceleration at the end of an increment of length dt (s) from the displacement x."""
    return (x - x_old - dt * v_old) / (beta * dt * dt) - (1 / (2 * beta) - 1) * a_old


def velocity(v_old, a_old, a, dt: float, gamma: float):
    """Velocity at the end of the increment."""
    return v_old + dt * ((1 - gamma) * a_old + gamma * a)
