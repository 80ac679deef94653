"""Physical effects, one module each; this registry says which are built for a scene.

- always: `elasticity` (the law follows `large_strain`, `plane_strain`/`plane_stress`)
  and `contact` (normal contact with the rigid body);
- when the scene names them, right after `elasticity`: the entries of `MATERIAL`, which
  change the stress that contact and the outputs read;
- when the scene names them in `effects`: the entries of `NAMED`;
- when the rigid shape calls for them: `rigid_corners` (sharp corners, 2-D P1).

Adding an effect: one module with an `Effect` subclass, one line in `NAMED` (or `MATERIAL`), and its
name in `femcontact.config.scene.EFFECTS` (docs/architecture.md).
"""
from femcontact.effects.compliant_support import CompliantSupport
from femcontact.effects.contact import NormalContact
from femcontact.effects.elasticity import Elasticity
from femcontact.effects.friction import Friction
from femcontact.effects.gravity import Gravity
from femcontact.effects.inertia import Inertia
from femcontact.effects.plasticity import Plasticity
from femcontact.effects.rigid_corners import RigidCorners

ALWAYS = (Elasticity, NormalContact)
MATERIAL = {"plasticity": Plasticity}
"""Effects on the material law, built when named, between `elasticity` and `contact`."""
NAMED = {"friction": Friction, "inertia": Inertia, "gravity": Gravity, "compliant_support": CompliantSupport}
"""Effects built when the scene names them, in the order they add their terms."""
BY_SHAPE = (RigidCorners,)


def components_for(problem) -> list:
    """The effect objects a scene calls for, in build order."""
    def named(registry):
        return [cls for name, cls in registry.items() if name in problem.effects]

    classes = [Elasticity, *named(MATERIAL), NormalContact, *named(NAMED)]
    classes += [cls for cls in BY_SHAPE if cls.applies(problem)]
    return [cls(problem) for cls in classes]
