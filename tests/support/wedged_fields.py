"""A wedged peg's fields.npz and the contact forces its lumped contact fields integrate to, for
the tests of fields.npz on one and two ranks."""
from pathlib import Path

import numpy as np

WEDGING_SCENE = Path(__file__).resolve().parents[2] / "scenes" / "wedging_2d.toml"
WEDGED = {"mesh.resolution": 0.5, "peg.corner_radius": 0.5}
"""The wedging scene on a coarse mesh, the peg's corners rounded: both contact zones press through
the contact integral (a sharp rigid corner's force is a point force, outside the contact fields:
docs/limitations.md)."""


def read_fields(path) -> dict:
    with np.load(path) as data:
        return {name: data[name] for name in data.files}


def contact_forces(fields: dict) -> dict:
    """Per zone (A: x < 0, B: x > 0): (magnitude of the force the lumped contact fields integrate
    to (N/mm), touching nodes). The sum over the zone's nodes of area x pressure is the normal
    force and of area x tangential traction the tangential force, exactly (the hat functions sum
    to 1); their magnitude is |F| when the normal is one across the zone's touching nodes."""
    x, area = fields["points"], fields["contact_area"]
    out = {}
    for zone, where in (("A", x[:, 0] < 0), ("B", x[:, 0] > 0)):
        normal = np.sum(area[where] * fields["contact_pressure"][where])
        tangential = np.sum(area[where, None] * fields["tangential_traction"][where], axis=0)
        out[zone] = (float(np.hypot(normal, np.linalg.norm(tangential))),
                     int(np.count_nonzero(fields["contact_pressure"][where] > 0)))
    return out
