"""Command-line interface: ``tengfield <command> ...``.

Each command lives in ``tengfield.commands.<name>`` with a ``register``
function; those modules import heavy dependencies only inside their
handlers, so ``tengfield dynamics`` never loads dolfinx or gmsh.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from . import __version__
from .errors import TengfieldError

# command modules, in the order `tengfield --help` lists them
COMMAND_MODULES = [
    "scene",
    "info",
    "dynamics",
    "field",
    "run",
    "precompute",
    "sweep",
    "report",
    "fit",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tengfield",
        description="Bouncing-ball TENG: impact dynamics, dolfinx electrostatics, "
                    "V_OC / Q_SC / I_SC waveforms. Without SCENE every command uses "
                    "the embedded default scene (the paper's device).")
    parser.add_argument("--version", action="version", version=f"tengfield {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"tengfield.commands.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except TengfieldError as exc:
        print(f"tengfield: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tengfield: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
