"""gmsh plumbing shared by the builders: sizes, polygons, physical groups, size fields.

Everything here runs on the rank that builds the gmsh model, except `Sizes`/`sizes`,
which every rank computes from the scene. gmsh (0.3-0.5 s to load) is imported by the
functions that call it, here and in the builders, so validating a scene never loads it.
"""
import math
from dataclasses import dataclass

GRADING = 0.15  # growth of the element size per unit distance from a fine zone (mm/mm)


@dataclass(frozen=True)
class Sizes:
    """Element sizes (mm). `contact` and `max` are the sizes of the base mesh (resolution 1);
    the mesh uses them divided by `resolution`; `zone` (half-length of each fine zone) and
    the grading distances do not depend on `resolution`, so refining scales the whole
    size field uniformly."""
    contact: float
    max: float
    zone: float
    resolution: float

    @property
    def h_contact(self) -> float:
        """Element size in the contact zones actually used (mm)."""
        return self.contact / self.resolution

    @property
    def h_max(self) -> float:
        """Largest element size actually used (mm)."""
        return self.max / self.resolution

    @property
    def grading_distance(self) -> float:
        """Distance from a fine zone over which the size grows from contact to max (mm)."""
        return (self.max - self.contact) / GRADING


def meshed_scale(scene: dict) -> float:
    """Length scale (mm) of the meshed peg-in-hole body: min(block_width, depth) for the
    hole block(s), min(width, length) for a meshed peg."""
    if scene["rigid"] == "peg":
        return min(scene["hole"]["block_width"], scene["hole"]["depth"])
    return min(scene["peg"]["width"], scene["peg"]["length"])


def sizes(mesh: dict, contact: float, size_max: float, zone: float) -> Sizes:
    """Sizes from the scene's `mesh` section; the defaults apply where it says 0."""
    h_c = mesh["contact_size"] or contact
    return Sizes(contact=h_c, max=max(mesh["size_max"] or size_max, h_c),
                 zone=mesh["contact_zone"] or zone, resolution=mesh["resolution"])


_initialized = False  # gmsh 4.8 has no gmsh.isInitialized()


def start(name: str) -> None:
    """Start (once per process) a quiet gmsh session, and a fresh model `name`."""
    import gmsh

    global _initialized
    if not _initialized:
        gmsh.initialize()
        _initialized = True
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    gmsh.model.add(name)


def reset() -> None:
    """End this process's gmsh session, if one was started: the next start() begins a new one with
    gmsh's default options (a study's warm worker calls this between cases)."""
    global _initialized
    if _initialized:
        import gmsh

        gmsh.finalize()
        _initialized = False


def polygon(vertices, edges) -> tuple[int, list[tuple[str | None, bool, int]]]:
    """Plane surface (built-in kernel) bounded by the closed polygon `vertices` [(x, y)];
    edges[i] = (name or None, fine) describes the edge from vertex i to vertex i + 1.
    Returns the surface tag and [(name, fine, line tag)] per edge."""
    import gmsh

    occ = gmsh.model.geo
    points = [occ.addPoint(x, y, 0.0) for x, y in vertices]
    lines = [occ.addLine(points[i], points[(i + 1) % len(points)]) for i in range(len(points))]
    surface = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    return surface, [(name, fine, line) for (name, fine), line in zip(edges, lines)]


def add_groups(dim: int, entities: dict[str, list[int]], first: int = 1) -> dict[str, int]:
    """One physical group per non-empty name, numbered from `first` in insertion order;
    returns name -> physical group number (the DOLFINx tag value)."""
    import gmsh

    groups = {}
    for name, tags in entities.items():
        if tags:
            number = first + len(groups)
            gmsh.model.addPhysicalGroup(dim, sorted(set(tags)), number)
            gmsh.model.setPhysicalName(dim, number, name)
            groups[name] = number
    return groups


def distance_threshold(sizes: Sizes, curves=(), surfaces=(), curve_length: float = 0.0) -> int:
    """Size field: sizes.h_contact on the given curves/surfaces, growing linearly with the
    distance to sizes.h_max over sizes.grading_distance. Curves are sampled at about a
    quarter of the contact size (`curve_length`: the longest curve)."""
    import gmsh

    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    if curves:
        field.setNumbers(distance, "CurvesList", list(curves))
        samples = math.ceil(4 * curve_length * sizes.resolution / sizes.contact) + 2
        field.setNumber(distance, "NumPointsPerCurve", samples)
    if surfaces:
        field.setNumbers(distance, "SurfacesList", list(surfaces))
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", sizes.h_contact)
    field.setNumber(threshold, "SizeMax", sizes.h_max)
    field.setNumber(threshold, "DistMin", 0.0)
    field.setNumber(threshold, "DistMax", sizes.grading_distance)
    return threshold


def graded(sizes: Sizes, distance: str) -> int:
    """MathEval size field: sizes.h_contact where the gmsh expression `distance` (mm) is 0,
    growing linearly with it to sizes.h_max over sizes.grading_distance."""
    import gmsh

    slope = GRADING / sizes.resolution
    expression = f"Min({sizes.h_max!r}, {sizes.h_contact!r}+{slope!r}*({distance}))"
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(field, "F", expression)
    return field


def ball_size(sizes: Sizes, centre, radius: float) -> int:
    """Size field `graded` by the distance to the ball of `radius` (mm) around `centre`."""
    x, y, z = centre
    r = f"Sqrt((x-({x!r}))^2+(y-({y!r}))^2+(z-({z!r}))^2)"
    return graded(sizes, f"Max(0, {r}-{radius!r})")


def background(fields: list[int]) -> None:
    """Use the minimum of the size `fields` as the only source of element sizes. (The fields
    carry the resolution themselves: gmsh 4.8 can hang evaluating a MathEval of a field.)"""
    import gmsh

    field = gmsh.model.mesh.field
    smallest = field.add("Min")
    field.setNumbers(smallest, "FieldsList", fields)
    field.setAsBackgroundMesh(smallest)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
