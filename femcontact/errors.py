"""Errors a user can cause: reported as one clear message, never a traceback."""
from geometry.errors import InputError

__all__ = ["InputError"]
