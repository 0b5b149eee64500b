"""``tengfield scene``: write out or check a scene file."""
from __future__ import annotations

import json
import sys


def register(sub) -> None:
    p = sub.add_parser("scene", help="print the default scene, or check a scene file",
                       description="`tengfield scene --default > my.toml` writes the embedded "
                                   "default scene with its comments; `tengfield scene FILE` "
                                   "checks FILE (every section any command reads, [design], "
                                   "[fit] and [uncertainty] included) and prints every key in SI-free file units.")
    p.add_argument("scene", nargs="?", help="scene file to check")
    p.add_argument("--default", action="store_true", help="print the commented default scene")
    p.set_defaults(func=_run)


def check_sections(scene) -> None:
    """The sections only one command reads, checked by that command's own validator
    (raises SceneError): ``[design]`` (design/spec.py), ``[fit]`` (fit/spec.py),
    ``[uncertainty]`` (uncertainty/spec.py). The other sections ([device] ...
    [breakdown], [array], [reference]) are checked when the scene is built."""
    if "design" in scene.raw:
        from ..design.spec import parse_design_section

        parse_design_section(scene)
    if "fit" in scene.raw:
        from ..fit.spec import parse_fit_section

        parse_fit_section(scene)
    if "uncertainty" in scene.raw:
        from ..uncertainty.spec import uncertainty_spec

        uncertainty_spec(scene)


def _run(args) -> int:
    from ..scene import default_text, load_scene

    if args.default or args.scene is None:
        sys.stdout.write(default_text())
        return 0
    scene = load_scene(args.scene)
    check_sections(scene)
    print(json.dumps(scene.to_dict(), indent=2))
    print(f"# field hash {scene.field_hash()}", file=sys.stderr)
    return 0
