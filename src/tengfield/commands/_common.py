"""Pieces several commands share (command modules never import each other)."""
from __future__ import annotations

import shlex
import sys
from pathlib import Path  # a scene argument is a file name, never TOML text


def scene_command(sub, name: str, *, help: str, description: str, output: str | None):
    """A subcommand taking an optional SCENE file and ``-o DIR`` (default ``output``;
    ``output=None``: no ``-o``, the command adds its own); ``description``: the
    command module's docstring or a sentence (reST quotes dropped)."""
    p = sub.add_parser(name, help=help, description=description.replace("``", ""))
    p.add_argument("scene", nargs="?", type=Path, help="scene file (default: the embedded default scene)")
    if output is not None:
        p.add_argument("-o", "--output", default=output, metavar="DIR",
                       help=f"output directory (created; default ./{output})")
    return p


def add_cache_argument(parser) -> None:
    """``--cache-dir DIR``: where surrogates are cached."""
    parser.add_argument("--cache-dir", default=None, metavar="DIR",
                        help="surrogate cache (default $TENGFIELD_CACHE_DIR, else "
                             "$XDG_CACHE_HOME/tengfield or ~/.cache/tengfield)")


def add_jobs_argument(parser) -> None:
    """``--jobs N``: worker processes on this machine; under ``mpirun -n N`` (N > 1)
    the ranks are the workers and --jobs must be omitted or 1
    (:func:`tengfield._mpi.check_jobs`)."""
    parser.add_argument("--jobs", "-j", type=int, default=None, metavar="N",
                        help="worker processes on this machine (default: all cores); under "
                             "mpirun -n N the MPI ranks are the workers: omit it or give 1")


def command_line() -> str:
    """The command line as typed (stored in the surrogate cache's provenance)."""
    return shlex.join(["tengfield", *sys.argv[1:]])
