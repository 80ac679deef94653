"""Gravity: the weight rho g of the deformable body (body force, -y in 2-D, -z in 3-D)
and the rigid body's weight m g at its reference point (N)."""
import numpy as np
import ufl

from femcontact.effects.base import Effect


class Gravity(Effect):
    name = "gravity"

    def __init__(self, problem):
        super().__init__(problem)
        n, dim = len(problem.rigid.names), problem.dim
        self.weight = np.zeros(n)
        self.weight[dim - 1] = -problem.rigid.mass * problem.scene["dynamics"]["gravity"]

    def constants(self, scene: dict, body: str) -> dict:
        return {"density": scene["materials"][body]["density"], "g": scene["dynamics"]["gravity"]}

    def build(self, problem) -> None:
        down = [0.0] * problem.dim
        down[-1] = -1.0
        weight = problem.constants["density"] * problem.constants["g"] * ufl.as_vector(down)
        problem.add_bulk(-ufl.dot(weight, problem.v))

    def rigid_residual(self, load) -> np.ndarray:
        return -self.weight

    def load_scale(self) -> float:
        return float(np.linalg.norm(self.weight))
