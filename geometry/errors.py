"""The one error type a user can cause; femcontact re-exports it as femcontact.errors.InputError."""


class InputError(ValueError):
    """Bad user input (scene, study or command-line value); the message names the key and value."""
