"""What an effect is: a small component that adds its terms to a `Problem` and owns its state.

Every hook has a do-nothing default, so an effect writes only what it needs:

- `constants(scene, body)`: initial values of the form constants it uses (a sweep changes
  their values without recompiling forms);
- `build(problem)`: add terms with `problem.add_bulk`, `add_contact_term`, `add_traction`;
- `begin_increment(load)` / `commit(dt)`: before an increment / after it converged;
  `commit_contacts()`: only the contact's history moved to the current state (friction anchors,
  slip), the material's and the motion's left at the increment's start: what a solver calls along
  a path that is not the loading path (pseudo-transient continuation);
- `lock_contacts(on)`: a friction law made to stick everywhere (on) or the scene's again (off),
  True if the effect has one (the solver's last way into an increment);
- `path_dependent()`: whether several equilibria may hold an increment's load, so that the
  answer depends on the path the solver takes to it (Coulomb friction: its equations have no
  potential);
- `state()` / `restore(state)`: copies of its history (to retry a cut increment, checkpoints);
- `rigid_residual(load)` / `rigid_stiffness(load)`: terms of the rigid body's equations;
- `add_contact_residual(vector)` / `add_contact_jacobian(matrices, kur, bc_dofs)`: entries of
  the contact vector not written as integrals (node-to-segment elements; `kur` maps each free
  rigid dof to the vector of their derivatives by it), and `point_contacts()`:
  the same forces for the contact fields (`outputs/fields.py`);
- `nodal_outputs()` (UFL values lumped to contact nodes, counted per row), `outputs()`
  (extra history columns) and `cell_fields()` (UFL values written per cell with the final
  fields); `load_scale()`: the size of the load it applies (N); `stiffness_scale()` and
  `contact_stiffness()`: the scales of the stiffness it adds (the solver's regularisation,
  stabilisation and round-off floor follow them).
"""
import numpy as np


class Effect:
    name = ""

    def __init__(self, problem):
        self.problem = problem

    def constants(self, scene: dict, body: str) -> dict:
        return {}

    def build(self, problem) -> None:
        pass

    def begin_increment(self, load) -> None:
        pass

    def commit(self, dt: float) -> None:
        pass

    def commit_contacts(self) -> None:
        pass

    def lock_contacts(self, on: bool) -> bool:
        return False

    def path_dependent(self) -> bool:
        return False

    def state(self) -> dict:
        return {}

    def restore(self, state: dict) -> None:
        pass

    def rigid_residual(self, load) -> np.ndarray | None:
        return None

    def rigid_stiffness(self, load) -> np.ndarray | None:
        return None

    def add_contact_residual(self, vector) -> None:
        pass

    def add_contact_jacobian(self, matrices, kur, bc_dofs: set) -> None:
        pass

    def point_contacts(self) -> list:
        """Point forces on the contact surface, not integrals, in the state now: (node a, node b, s,
        f_n, f_t, stick) each, a force at s in [0, 1] along the facet a-b (this rank's local nodes),
        normal part f_n >= 0 and tangential vector f_t (N, per mm of thickness in 2-D) on the
        deformable body, stick: whether it sticks."""
        return []

    def nodal_outputs(self) -> dict:
        return {}

    def outputs(self) -> dict:
        return {}

    def cell_fields(self) -> dict:
        return {}

    def load_scale(self) -> float:
        return 0.0

    def stiffness_scale(self) -> float:
        """A modulus (MPa) setting the scale of the bulk stiffness it adds; 0 if none."""
        return 0.0

    def contact_stiffness(self) -> float:
        """Stiffness of its contact term against a gap (N/mm^3); 0 if none."""
        return 0.0
