"""Errors of the geometry package."""


class GeometryError(ValueError):
    """A geometry or mesh that cannot or should not be built; the message names the scene keys."""
