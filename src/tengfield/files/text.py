"""Text files, written atomically (:func:`tengfield.files.atomic.atomic_path`):
:func:`write_text`, :func:`write_json` (strict JSON, NaN -> null) and
:func:`scene_toml` (a scene dict as TOML: fitted, recommended and best scenes, every
section whole, sub-tables included); :func:`one_line`, the one escaping of a
user-supplied text (a scene's path, a ``--set``) quoted into a comment, a header or a
title line of any file (issue #54.2)."""
from __future__ import annotations

import json
import os
import re
from pathlib import Path

from .._json import jsonable
from .atomic import atomic_path


def write_text(path: str | Path, text: str) -> Path:
    """``text`` to ``path``, atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def one_line(text) -> str:
    """``text`` (a scene's path, a ``--set`` setting, any user-supplied name or value) as
    one printable line, to quote into a line of a file (a netlist or TOML comment, a
    Markdown line, a header): a backslash is written ``\\\\``, a newline ``\\n``, a
    carriage return ``\\r``, a tab ``\\t``, any other character that is not printable
    (controls, the Unicode line and paragraph separators, format characters)
    ``\\xNN``, ``\\uNNNN`` or ``\\UNNNNNNNN``, as Python's string escapes; the rest as
    it is. So a quoted name can neither end the line it is in nor start a live one
    (issue #54.2: a scene file named ``run\\nRleak out 0 1k\\n*.toml`` put a resistor
    into teng.lib)."""
    return "".join(_escaped(c) for c in str(text))


_ESCAPES = {"\\": "\\\\", "\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escaped(c: str, backslash: bool = True) -> str:
    if c in _ESCAPES and (backslash or c != "\\"):
        return _ESCAPES[c]
    if c.isprintable():
        return c
    code = ord(c)
    return (f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000
            else f"\\U{code:08x}")


def write_json(path: str | Path, data) -> Path:
    """``data`` as indented strict JSON (NaN -> null, see :func:`tengfield._json.jsonable`)."""
    return write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


# ---------------------------------------------------------------------------
# TOML
def toml_value(value) -> str:
    """A TOML literal for a bool, int, float (``inf``, ``-inf``, ``nan`` included), string
    or list of them; ``TypeError`` for anything else."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)                # always has ".", "e", "inf" or "nan": a TOML float
    if isinstance(value, str):
        return json.dumps(value)          # a TOML basic string is a JSON string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):           # an inline table (a table inside a list)
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()
                                if v is not None) + " }"
    raise TypeError(f"cannot write {value!r} to TOML")


_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_key(key) -> str:
    """A TOML key: bare when it can be (``samples``), else quoted
    (``"contact.restitution"``: a dotted name inside ``[uncertainty.vary]`` is one key)."""
    key = str(key)
    return key if _BARE_KEY.match(key) else json.dumps(key)


def scene_dir(source: str) -> Path:
    """The folder a scene's relative file names resolve from: its file's folder, or the
    working directory for a scene without a file (``"<default>"``, ``"<dict>"``), as
    :meth:`tengfield.scene.Scene.with_values` reads them."""
    if source in ("<default>", "<dict>", "") or source.startswith("<"):
        return Path.cwd()
    return Path(source).parent


def _is_file_key(key: str) -> bool:
    """A key naming a file (``file``, ``psd_file``, ...)."""
    return key == "file" or key.endswith("_file")


def _file_value(key: str, value, base_dir: Path | None):
    """``value`` of a file key as an absolute path (resolved from ``base_dir``), so that
    the written scene runs from wherever it lives (issue #30.6: a fitted.toml in ``-o``
    kept ``file = "rec.csv"`` relative to the original scene and did not run)."""
    if base_dir is None or not _is_file_key(key) or not isinstance(value, str) or not value:
        return value
    if os.path.isabs(value):
        return value
    return os.path.abspath(os.path.join(os.fspath(base_dir), value))


def comment_lines(header: str, prefix: str) -> list[str]:
    """``header``'s lines (split at ``\\n`` only) behind ``prefix`` (``"# "`` in TOML,
    ``"* "`` in a netlist), each with :func:`one_line`'s escapes of what is not printable
    (a backslash kept: a name the writer quoted through :func:`one_line` reads the same):
    a comment whatever a name quoted without it held."""
    if not header:
        return []
    return [prefix + "".join(_escaped(c, backslash=False) for c in line)
            for line in str(header).split("\n")]


def scene_toml(data: dict, header: str = "", *, base_dir: str | Path | None = None) -> str:
    """TOML text of a scene dict (``{section: {key: value}}``): ``header`` as comment
    lines, then one table per section, each written whole: its scalars, then each
    sub-table under its own header (``[uncertainty.vary]``, ``[design.excitation]``,
    nested as deep as given), so that reading the text back gives ``data`` (issue #43.1:
    sub-tables were dropped while their parent's scalars stayed). Left out: an entry at
    the top level that is no section, a None. ``base_dir``: the folder the original
    scene's relative file names (``file``, ``psd_file``) resolve from
    (:func:`scene_dir`); they are written as absolute paths, since the written scene
    lives elsewhere (in ``-o``)."""
    lines = comment_lines(header, "# ")
    base = None if base_dir is None else Path(base_dir)

    def table(path: list[str], values: dict) -> None:
        lines.extend(["", "[" + ".".join(toml_key(p) for p in path) + "]"])
        lines.extend(f"{toml_key(key)} = {toml_value(_file_value(key, v, base))}"
                     for key, v in values.items() if v is not None and not isinstance(v, dict))
        for key, v in values.items():
            if isinstance(v, dict):
                table([*path, key], v)

    for sec, values in data.items():
        if isinstance(values, dict):
            table([sec], values)
    return "\n".join(lines).lstrip("\n") + "\n"
