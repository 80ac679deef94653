"""Errors a user can cause: reported as one clear message, never a traceback."""


class InputError(ValueError):
    """Bad user input (scene, study or command-line value); the message names the key and value."""
