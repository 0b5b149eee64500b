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


# -- a data file's text is never shown (#43 item 10) -------------------------------------
# A message about a file the user named (a recorded excitation, a PSD table, fit's measured
# trace) names the file, the line and what was expected, never the file's own text: the
# file may be any file (``--set excitation.file=/etc/shadow``, a credentials file), and a
# 100 KB header would be a 100 KB line. The readers' error paths describe a file's header
# and cells through these two helpers only.
def header_described(header) -> str:
    """A file's header as a message names it: how many columns it has, never their names."""
    n = len(header)
    return f"its header has {n} column{'s' if n != 1 else ''}"


def same_name_in_file(name: str, header) -> str:
    """`` (did you mean 'Time_s'?)`` when one of a file's column names is ``name`` written
    another way (case, spaces, ``-``/``_``, a letter or two: difflib ratio >= 0.8 of
    the folded names) and is a plain name (letters, digits, ``_ -.()/``, at most 64
    characters): what the user wrote, nearly; nothing else of the file's text; else ``""``."""
    import difflib
    import re

    def folded(text):
        return "".join(ch for ch in str(text).lower() if ch not in " -_")

    plain = [c for c in header if c != name and re.fullmatch(r"[A-Za-z0-9_ .()/-]{1,64}", c)]
    by_fold = {folded(c): c for c in plain}
    close = difflib.get_close_matches(folded(name), list(by_fold), n=1, cutoff=0.8)
    return f" (did you mean {by_fold[close[0]]!r}?)" if close and folded(name) else ""


class SurrogateError(TengfieldError, RuntimeError):
    """A surrogate file is missing, partial, corrupt or for another scene.

    ``path`` (if any) names the file and ``reason`` says what is wrong with it
    (the message without the path).
    """

    def __init__(self, message: str, *, path=None, reason: str | None = None):
        super().__init__(message)
        self.path = None if path is None else str(path)
        self.reason = reason if reason is not None else message
