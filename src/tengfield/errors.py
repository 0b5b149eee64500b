"""Exceptions tengfield raises for users: the CLI prints them without a traceback."""


class TengfieldError(Exception):
    """Base class of every error meant for the user."""


class SceneError(TengfieldError, ValueError):
    """Bad scene input: the message names the key, the value and the allowed range."""


class DynamicsError(TengfieldError, RuntimeError):
    """The dynamics could not be integrated (e.g. the event bound was exceeded)."""


class FieldError(TengfieldError, RuntimeError):
    """A field solve failed or was asked for something it cannot do."""


class OutputError(TengfieldError):
    """The output location cannot be used (not a directory, not writable, locked)."""
