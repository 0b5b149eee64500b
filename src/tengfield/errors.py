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


def show_number(value: float, *bounds: float) -> str:
    """``value`` for an out-of-range message beside its ``bounds``: ``:g``, with as many
    more digits as it takes not to read as a bound it differs from (``3.0000000001`` beside
    3, not ``3 is out of range: allowed [0, 3]``)."""
    for digits in range(6, 18):
        text = f"{value:.{digits}g}"
        if not any(b != value and text == f"{b:.{digits}g}" for b in bounds):
            return text
    return repr(value)
