"""A wedged peg's fields.npz and the contact forces its lumped contact fields integrate to, for
the tests of fields.npz on one and two ranks."""
from pathlib import Path

import numpy as np

WEDGING_SCENE = Path(__file__).resolve().parents[2] / "scenes" / "wedging_2d.toml"
WEDGED = {"mesh.resolution": 0.5}
"""The wedging scene on a coarse mesh: block A's corner presses the peg's flat side (the contact
integral), the peg's sharp corner presses wall B (a point force shared by the two nodes of the
facet it touches)."""


def read_fields(path) -> dict:
    with np.load(path) as data:
        return {name: data[name] for name in data.files}


def contact_forces(fields: dict) -> dict:
    """Per zone (A: x < 0, B: x > 0): (magnitude of the force the lumped contact fields integrate
    to (N/mm), touching nodes). The sum over the zone's nodes of area x pressure is the normal
    force and of area x tangential traction the tangential force, exactly (the hat functions sum
    to 1, and a point force is shared as its hat functions share it); their magnitude is |F| when
    the normal is one across the zone's touching nodes."""
    x, area = fields["points"], fields["contact_area"]
    out = {}
    for zone, where in (("A", x[:, 0] < 0), ("B", x[:, 0] > 0)):
        normal = np.sum(area[where] * fields["contact_pressure"][where])
        tangential = np.sum(area[where, None] * fields["tangential_traction"][where], axis=0)
        out[zone] = (float(np.hypot(normal, np.linalg.norm(tangential))),
                     int(np.count_nonzero(fields["contact_pressure"][where] > 0)))
    return out
