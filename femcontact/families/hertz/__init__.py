"""The Hertz benchmark: a rigid cylinder (2-D) or sphere (3-D) pressed on a block, against the
closed form (docs/references.md). Scenes of geometry 'block'; made in code at a contact-zone size
by `benchmark.scene` / `scene_3d`, or from a file (scenes/hertz.toml); no metrics of its own
in a study (`femcontact hertz`, `cli.py`, measures a and p0)."""
from femcontact.families.family import Family


def _scene(contact_size: float, **kwargs) -> dict:
    from femcontact.families.hertz.benchmark import scene

    return scene(contact_size, **kwargs)


FAMILY = Family(name="hertz", doc="docs/references.md", claims=lambda scene: scene["geometry"] == "block",
                scene_factory=_scene)
