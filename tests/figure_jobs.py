"""Jobs for the figure-process tests (tests/cli/test_figure_process.py): importable in the
child through PYTHONPATH."""
import os
import sys
from pathlib import Path


def noisy(path):
    """Prints to stdout and stderr (must not corrupt the answers), writes ``path``."""
    print("drawing", path)
    print("a warning", file=sys.stderr)
    Path(path).write_text("figure")
    return os.getpid()


def broken(value):
    raise ValueError(f"cannot draw {value!r}")


def unpicklable():
    return lambda: None


def die():
    os._exit(3)


def chatty():
    """What matplotlib says on a fresh machine, and a warning of a figure."""
    import logging
    import warnings

    logging.getLogger("matplotlib.font_manager").warning(
        "Matplotlib is building the font cache; this may take a moment.")
    warnings.warn("odd axis limits", UserWarning)
    return os.getpid()
