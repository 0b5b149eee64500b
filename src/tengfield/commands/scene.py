"""``tengfield scene``: write out or check a scene file."""
from __future__ import annotations

from pathlib import Path  # a scene argument is a file name, never TOML text

import json
import sys


def register(sub) -> None:
    p = sub.add_parser("scene", help="print the default scene, or check a scene file",
                       description="`tengfield scene --default > my.toml` writes the embedded "
                                   "default scene with its comments; `tengfield scene FILE` "
                                   "checks FILE (every section any command reads, [design], "
                                   "[fit] and [uncertainty] included) and prints every key in "
                                   "file units as TOML, a scene file that loads back to the "
                                   "same scene (--json: as JSON).")
    p.add_argument("scene", nargs="?", type=Path, help="scene file to check")
    p.add_argument("--default", action="store_true", help="print the commented default scene")
    p.add_argument("--json", action="store_true",
                   help="print the checked scene as JSON instead of TOML")
    p.set_defaults(func=_run)


def check_sections(scene) -> None:
    """The sections only one command reads, checked by that command's own validator
    (raises SceneError): ``[design]`` (design_study/spec.py), ``[fit]`` (fit/spec.py),
    ``[uncertainty]`` (uncertainty_study/spec.py). The other sections ([device] ...
    [breakdown], [array], [reference]) are checked when the scene is built."""
    if "design" in scene.raw:
        from ..design_study.spec import parse_design_section

        parse_design_section(scene)
    if "fit" in scene.raw:
        from ..fit.spec import parse_fit_section

        parse_fit_section(scene)
    if "uncertainty" in scene.raw:
        from ..uncertainty_study.spec import uncertainty_spec

        uncertainty_spec(scene)


def _run(args) -> int:
    from ..files import one_line
    from ..scene import default_text, load_scene

    if args.default or args.scene is None:
        sys.stdout.write(default_text())
        return 0
    scene = load_scene(args.scene)
    check_sections(scene)
    data = scene.to_dict()
    for name, section in scene.raw.items():   # [design], [fit], [uncertainty] as given
        if name not in data and isinstance(section, dict):
            data[name] = section
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        sys.stdout.write(toml_text(data, f"tengfield scene: {one_line(scene.source)}, every "
                                         "key checked, in file units"))
    print(f"# field hash {scene.field_hash()}", file=sys.stderr)
    return 0


def toml_text(data: dict, header: str = "") -> str:
    """``{section: {key: value or sub-table}}`` as TOML: ``header`` as comment lines, each
    table's values, then its sub-tables (``[design.vary]``); a None value (a key left
    unset) as a comment."""
    from ..files import comment_lines, toml_value

    lines = comment_lines(header, "# ")

    def table(name: str, values: dict) -> None:
        lines.extend(["", f"[{name}]"])
        for key, value in values.items():
            if isinstance(value, dict):
                continue
            if value is None:
                lines.append(f"# {key}: unset")
            else:
                plain = list(value) if isinstance(value, tuple) else value
                lines.append(f"{_key(key)} = {toml_value(plain)}")
        for key, value in values.items():
            if isinstance(value, dict):
                table(f"{name}.{_key(key)}", value)

    for name, values in data.items():
        if isinstance(values, dict):
            table(_key(name), values)
    return "\n".join(lines).lstrip("\n") + "\n"


def _key(key: str) -> str:
    """A TOML key: bare when it can be (letters, digits, _ and -), else quoted."""
    import re

    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)
