"""Elasticity of the deformable body (always built).

The law follows the scene's effects: Hooke, or St Venant-Kirchhoff with `large_strain`;
in 2-D plane strain (default) or `plane_stress`. Provides `problem.stress`,
`problem.energy_density` and `problem.von_mises` for contact and outputs.
"""
import ufl

from femcontact.effects.base import Effect
from femcontact.physics import elasticity as law


class Elasticity(Effect):
    name = "elasticity"

    def constants(self, scene: dict, body: str) -> dict:
        material = scene["materials"][body]
        return {"E": material["E"], "nu": material["nu"]}

    def build(self, problem) -> None:
        c, effects = problem.constants, problem.effects
        large, plane_stress = "large_strain" in effects, "plane_stress" in effects
        lmbda, mu = law.lame(c["E"], c["nu"], plane_stress)
        u = problem.u
        stress = law.svk_first_piola(u, lmbda, mu) if large else law.hooke_stress(u, lmbda, mu)
        problem.stress = stress
        problem.add_bulk(ufl.inner(stress, ufl.grad(problem.v)))
        problem.energy_density = law.energy_density(u, lmbda, mu, large)
        plane = None if problem.dim == 3 else "plane_stress" if plane_stress else "plane_strain"
        problem.von_mises = law.von_mises(stress, lmbda, mu, plane)

    def stiffness_scale(self) -> float:
        """Young's modulus E (MPa)."""
        return float(self.problem.constants["E"].value)
