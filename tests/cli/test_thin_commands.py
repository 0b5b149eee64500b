"""The CLI commands are thin (issue #41): parse, call the verb, ``result.write(...)``.
No ``commands/*.py`` calls a file writer of its own (a ``write_*`` function of
``io``, ``files`` or a package's ``output`` module): the files a command writes are
the ones its result's ``.write`` writes from Python."""
from __future__ import annotations

import ast
from pathlib import Path

import tengfield.commands

COMMANDS = Path(tengfield.commands.__file__).parent

#: the one writer call a command keeps, with its reason
KEPT = {
    # the -o FILE / cache entry is one file, not an output directory
    ("precompute.py", "write_table"),
}


def writer_calls(path: Path) -> set[str]:
    """The ``write_*`` names ``path`` calls (``write_x(...)`` or ``module.write_x(...)``)
    and imports."""
    tree = ast.parse(path.read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) \
                else ""
            if name.startswith("write_") or name in ("export",):
                names.add(name)
        elif isinstance(node, ast.ImportFrom):
            names.update(a.name for a in node.names
                         if a.name.startswith("write_") or a.name == "export")
    return names


def test_no_command_calls_a_writer_of_its_own():
    found = {(p.name, name) for p in sorted(COMMANDS.glob("*.py")) for name in writer_calls(p)}
    assert found - KEPT == set(), sorted(found - KEPT)


def test_the_check_sees_a_writer_call(tmp_path):
    """The check itself: a command that writes summary.json itself is caught."""
    sample = tmp_path / "sample.py"
    sample.write_text("from ..io import write_json\n\ndef _run(args):\n"
                      "    write_json(args.output, {})\n    io.write_sweep_csv(1, 2)\n")
    assert writer_calls(sample) == {"write_json", "write_sweep_csv"}
