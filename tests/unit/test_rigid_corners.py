"""The surface a sharp rigid corner presses (effects/rigid_corners.py): the projection along the
normal smoothed at the nodes, against closed forms on a dimpled surface."""
import numpy as np
import pytest

from femcontact.effects.rigid_corners import _end_normals, _outward, _projection

# A surface y = 0 with a dimple at its middle node: the node at x = 0 pushed down by 0.01 mm, as
# a corner pressing there dents it; the body lies below (y < 0). Two facets of 1 mm.
NODES = np.array([[-1.0, 0.0], [0.0, -0.01], [1.0, 0.0]])
AWAY = np.array([[0.0, 1.0], [0.0, 1.0]])  # from inside the body to each facet


def _gap_and_normal(corner):
    """Gap (mm) and normal of `corner` on the facet it projects inside, smoothed at the middle node."""
    edges = NODES[1:] - NODES[:-1]
    own = _outward(edges, AWAY)
    neighbour = np.full((2, 2, 2), np.nan)
    neighbour[0, 1], neighbour[1, 0] = own[1], own[0]  # the middle node is shared
    ends = _end_normals(own, neighbour)
    for facet in range(2):
        s = _projection(corner - NODES[facet], edges[facet], ends[facet, 0], ends[facet, 1])
        if -1e-12 <= s <= 1 + 1e-12:
            normal = ends[facet, 0] + s * (ends[facet, 1] - ends[facet, 0])
            normal /= np.linalg.norm(normal)
            return (corner - NODES[facet] - s * edges[facet]) @ normal, normal
    return None


def test_a_corner_in_its_own_dimple_projects_on_the_node():
    """Under the dented node, inside the body, the straight projection finds neither facet (the
    wedge between their normals); the smoothed one lands on the node with the vertical normal."""
    corner = np.array([0.0, -0.012])
    edges = NODES[1:] - NODES[:-1]
    straight = [(corner - NODES[i]) @ edges[i] / (edges[i] @ edges[i]) for i in range(2)]
    assert straight[0] > 1 and straight[1] < 0  # the gap of one normal per facet
    gap, normal = _gap_and_normal(corner)
    assert gap == pytest.approx(-0.002, rel=1e-9)
    assert normal == pytest.approx([0.0, 1.0], abs=1e-12)


def test_the_gap_is_continuous_as_a_corner_passes_the_node():
    """Swept across the node at 2 um below it, the gap changes smoothly: its jump between samples
    1e-4 mm apart stays at the slope of the facets times the step (0.01 x 1e-4 mm), never a jump."""
    xs = np.linspace(-0.05, 0.05, 1001)
    gaps = np.array([_gap_and_normal(np.array([x, -0.012]))[0] for x in xs])
    assert np.all(gaps < 0)
    assert np.abs(np.diff(gaps)).max() < 2 * 0.01 * (xs[1] - xs[0])


@pytest.mark.parametrize("point, expected", [((0.3, 0.5), 0.3), ((0.7, -0.2), 0.7)])
def test_a_straight_facet_projects_perpendicularly(point, expected):
    """Equal nodal normals: the quadratic is linear and gives the perpendicular foot."""
    up = np.array([0.0, 1.0])
    assert _projection(np.array(point), np.array([1.0, 0.0]), up, up) == pytest.approx(expected, abs=1e-14)
