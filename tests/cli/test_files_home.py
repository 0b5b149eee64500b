"""One home for writing files (issue #41): the primitives live in ``tengfield.files``;
the writers compose them. A write that fails leaves the old file and no temporary."""
from __future__ import annotations

import ast
import errno
from pathlib import Path

import pytest

import tengfield
from tengfield.files import atomic, write_bytes, write_figure

SRC = Path(tengfield.__file__).parent

#: the calls that put bytes on disk or move them into place: only tengfield.files makes
#: them (plotting.save_figure renders a Figure into the path write_figure hands it)
PRIMITIVES = {"replace", "mkstemp", "NamedTemporaryFile", "savetxt", "savefig", "fsync"}
ALLOWED = {"files/", "plotting/__init__.py", "plotting/process.py"}


def primitive_calls(path: Path) -> set[str]:
    text = path.read_text()
    names = set()
    if not any(f".{name}(" in text for name in PRIMITIVES):    # most files: no AST needed
        return names
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and node.func.attr in PRIMITIVES and not (
                    node.func.attr == "replace" and not _is_os(node.func.value)):
            names.add(node.func.attr)
    return names


def _is_os(value) -> bool:
    return isinstance(value, ast.Name) and value.id == "os"


def test_no_writer_outside_files_holds_a_primitive():
    found = {}
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).as_posix()
        if any(rel == a or rel.startswith(a) for a in ALLOWED):
            continue
        calls = primitive_calls(path)
        if calls:
            found[rel] = sorted(calls)
    assert found == {}, found


def test_the_scan_sees_a_primitive(tmp_path):
    sample = tmp_path / "writer.py"
    sample.write_text("import os\n\ndef w(tmp, p):\n    os.replace(tmp, p)\n"
                      "    'a'.replace('a', 'b')\n")
    assert primitive_calls(sample) == {"replace"}


def test_write_bytes_replaces_whole_or_not_at_all(tmp_path, monkeypatch):
    target = tmp_path / "table.h5"
    write_bytes(target, b"old")
    assert target.read_bytes() == b"old"

    def full_disk(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full_disk)
    with pytest.raises(OSError, match="table.h5"):              # the error names the file
        write_bytes(target, b"new")
    assert target.read_bytes() == b"old"                          # the old file intact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.h5"]   # no temporary left


def test_write_figure_leaves_no_partial_figure(tmp_path):
    def draw(text, path):
        Path(path).write_text(text)
        if text == "broken":
            raise RuntimeError("the figure failed half way")

    target = tmp_path / "waveforms.png"
    assert write_figure(draw, "first", path=target) == target
    with pytest.raises(RuntimeError):
        write_figure(draw, "broken", path=target)
    assert target.read_text() == "first"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["waveforms.png"]
