"""Scene files: TOML text -> :class:`~tengfield.scene.model.Scene`.

Reading refuses what tomllib would choke on before it does (size, NUL characters,
nesting), and what no scene key takes (TOML dates, integers beyond the doubles); the
values themselves are checked by :func:`tengfield.scene.model.build`.
"""
from __future__ import annotations

import copy
import datetime
import os
import re
import tomllib
import warnings
from importlib import resources
from pathlib import Path

from ..files import file_kind, note_input
from .._mpi import launched_rank
from ..errors import SceneError
from .limits import MAX_SCENE_BYTES, MAX_TOML_DEPTH
from .model import Scene, build
from .recorded import decode_utf8
from .schema import RENAMED_KEYS, SCHEMA, show, update_section
from ..quantities import MAX_MEASURED, MIN_MEASURED
from .shapes import keys_of_other_shapes, switched_shape


def default_text() -> str:
    """The embedded default scene, with its comments."""
    return resources.files("tengfield").joinpath("data/default.toml").read_text()


def default_scene() -> Scene:
    return parse_scene(default_text(), source="<default>")


def _is_toml_text(text: str) -> bool:
    """A str ``load_scene`` reads as TOML rather than as a file name: it names no
    existing file and holds a line break, a ``=`` or starts with ``[`` (the command line
    hands a ``Path``: always a file name)."""
    if os.path.exists(text):
        return False
    return "\n" in text or "=" in text or text.lstrip().startswith("[")


def load_scene(path: "str | Path | Scene | None") -> Scene:
    """Read a scene file, or TOML text (a str with a line break, a ``key = value``, a
    ``[section]``, naming no existing file); ``None`` gives the embedded default scene; a
    :class:`Scene` is returned as it is (the CLI hands its commands a scene with ``--set`` applied)."""
    if isinstance(path, Scene):
        return path
    if path is None:
        return default_scene()
    if isinstance(path, str) and _is_toml_text(path):   # the README's "or TOML text"
        return parse_scene(path, source="<TOML text>")
    from .._args import check_path_argument
    check_path_argument("tengfield.load_scene", path)
    p = Path(path)
    if p.is_dir():
        raise SceneError(f"scene file {str(p)!r} is a directory: give a .toml file")
    if not p.is_file():
        try:
            kind = file_kind(os.stat(p).st_mode)   # a FIFO, a device: named, not "missing"
        except OSError:
            raise SceneError(f"scene file {str(p)!r} does not exist") from None
        raise SceneError(f"scene file {str(p)!r} is {kind}, not a regular file: give a .toml file")
    try:
        size = p.stat().st_size
        if size > MAX_SCENE_BYTES + 4:   # before reading: a 50 MB file is refused at once
            raise SceneError(f"scene file {str(p)!r} has {size:,} bytes: allowed at most "
                             f"{MAX_SCENE_BYTES:,} (recorded data belong in a CSV file)")
        note_input(p)     # never replaced or removed by the command's outputs
        blob = p.read_bytes()
    except OSError as exc:
        raise SceneError(f"scene file {str(p)!r} could not be read: {exc.strerror or exc}") from None
    return parse_scene(decode_utf8(blob, f"scene file {str(p)!r}"), source=str(p),
                       base_dir=p.parent)


def parse_scene(text: str, *, source: str = "<string>", base_dir: Path | None = None) -> Scene:
    text = text.removeprefix("\ufeff")   # a UTF-8 byte-order mark is not TOML
    if len(text) > MAX_SCENE_BYTES:
        raise SceneError(f"{source}: {len(text):,} characters: a scene file is allowed at most "
                         f"{MAX_SCENE_BYTES:,} (recorded data belong in a CSV file)")
    if "\x00" in text:
        raise SceneError(f"{source}: holds NUL characters (binary data, not a TOML scene)")
    _check_nesting_text(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: malformed TOML: {exc}") from None
    except RecursionError:
        raise SceneError(f"{source}: nested too deeply: allowed {MAX_TOML_DEPTH} levels of "
                         "tables and arrays") from None
    except (ValueError, OverflowError) as exc:   # e.g. an integer of more than 4300 digits
        long = re.search(r"[0-9_]{4000,}", text)
        if long:
            line = text.count("\n", 0, long.start()) + 1
            key = text[text.rfind("\n", 0, long.start()) + 1:long.start()].split("=")[0].strip()
            raise SceneError(f"{source}: line {line}: {key} = an integer of "
                             f"{long.end() - long.start()} digits is out of range: numbers must "
                             "stay within the doubles (|x| < 1.8e308)") from None
        detail = str(exc).split(";")[0].strip()
        raise SceneError(f"{source}: malformed TOML: {detail}") from None
    _check_values(data, source)
    scene = build(data, base_dir=base_dir, source=source, text=text)
    check_rules(scene)
    return scene


#: the largest noise seed (numpy's SeedSequence takes any integer; the scene's range)
MAX_SEED = 2**32 - 1


def check_rules(scene: Scene, before: Scene | None = None) -> None:
    """What a scene file says that a command would refuse or leave out later, said when
    the file is read (``tengfield scene`` included): an [array] with a contact model other
    than the impact map (the rule of :func:`tengfield.array.check_array_scene`), ensemble
    seeds past 2^32 - 1 (they wrapped to 0, 1, ...), and two warnings: penetration_max_mm
    with the Hertz law (it only shapes the power law's damping) and an ``[instrument]``
    sample rate below twice the excitation's frequency (its readings alias; not again
    for ``--set`` on a file, ``before``, that gave the same rate and frequency)."""
    if scene.array.cells > 0 and scene.contact.model != "impact":
        raise SceneError(f"[contact] model = {scene.contact.model!r}: [array] runs need the "
                         "impact map (model = 'impact')")
    exc, runs = scene.excitation, scene.run.realisations
    if runs > 1 and exc.seed + runs - 1 > MAX_SEED:
        raise SceneError(f"[excitation] seed = {exc.seed} with [run] realisations = {runs}: the "
                         f"realisations use seeds {exc.seed} ... {exc.seed + runs - 1}; allowed "
                         f"seed + realisations - 1 <= {MAX_SEED} (seed <= {MAX_SEED - runs + 1})")
    for key, value in (scene.raw.get("reference") or {}).items():
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value != 0 \
                and abs(value) < MIN_MEASURED:   # its SI value would be 0: "not given"
            raise SceneError(f"[reference] {key} = {value!r} is out of range: allowed 0 (not "
                             f"given) or [{MIN_MEASURED:g}, {MAX_MEASURED:g}] (a measured "
                             "magnitude in the key's unit)")
    device = scene.raw.get("device") or {}
    others = keys_of_other_shapes(scene.device.shape, [   # a default (a tool's own file of
        k for k, v in device.items()                      # every key) is not a user's value
        if not (k in SCHEMA["device"] and v == SCHEMA["device"][k].default)])
    if others and scene.device.shape != "spherical-shell" and launched_rank() == 0:
        import warnings
        warnings.warn(f"[device] {', '.join(others)} left out: key(s) of another shape than "
                      f"shape = {scene.device.shape!r} (set [device] shape to use them)",
                      RuntimeWarning, stacklevel=3)
    rate, exc = scene.instrument.sample_rate, scene.excitation
    said = before is not None and (before.instrument.sample_rate,
                                   before.excitation.frequency) == (rate, exc.frequency)
    if 0.0 < rate < 2.0 * exc.frequency and exc.kind != "random" and not said \
            and launched_rank() == 0:
        import warnings      # below Nyquist: the readings alias (a refusal: too few of them)
        warnings.warn(
            f"[instrument] sample_rate_hz = {rate:g} takes {rate / exc.frequency:.3g} "
            f"reading(s) per period of [excitation] frequency_hz = {exc.frequency:g}, "
            "fewer than 2 (Nyquist): the read columns and their peaks alias the device's "
            f"(sample_rate_hz >= {2.0 * exc.frequency:g} resolves the period)",
            RuntimeWarning, stacklevel=3)
    contact = scene.contact
    if contact.law == "hertz" and contact.penetration_max > 0.0:
        import warnings
        warnings.warn(f"[contact] penetration_max_mm = {contact.penetration_max * 1e3:g} left "
                      "out: it shapes the damping of law = 'power' only (law = 'hertz' damps "
                      "by [contact] damping_model)", RuntimeWarning, stacklevel=3)


def parse_setting(text: str, option: str = "--set") -> tuple[list[str], object]:
    """``section.key=value`` (``--set``) -> (``["section", "key"]``, value). The value is
    read as a TOML value (``30``, ``1e8``, ``"rectifier"``, ``[1.0, 4.0]``, ``true``);
    a bare word that is no TOML value is a string (``kind=rectifier``). Messages name
    ``option``, the command-line option the text came from (``--vary`` reads its values
    here too)."""
    if "\n" in text or "\r" in text:   # TOML would read the first line and drop the rest
        raise SceneError(f"{option} {text.splitlines()[0][:80]!r}...: the value holds a line "
                         "break; allowed one line (a list as [a, b], a string in quotes)")
    name, eq, value = _split_setting(text)
    path = _key_path(name)
    if not eq or path is None or len(path) < 2 or not all(path):
        raise SceneError(f"{option} {text!r}: write section.key=value, e.g. "
                         "--set excitation.frequency_hz=30 (a dotted key quoted: "
                         "--set 'uncertainty.vary.\"contact.restitution\".high=0.8')")
    value = value.strip()
    try:
        parsed = tomllib.loads(f"v = {value}")["v"]
    except (tomllib.TOMLDecodeError, ValueError, OverflowError, RecursionError):
        if not re.fullmatch(r"[A-Za-z0-9_+\-./]+", value or "?"):
            raise SceneError(f"{option} {text!r}: {value!r} is no TOML value (numbers as "
                             "written, strings in quotes, lists as [a, b])") from None
        parsed = value
    nested = parsed
    for part in reversed(path):   # the key's own name in the message ([run] duration_s)
        nested = {part: nested}
    _check_values(nested, option)
    return path, parsed


def _split_setting(text: str) -> tuple[str, str, str]:
    """``text`` split at its first ``=`` outside a quoted key part."""
    quote = None
    for i, ch in enumerate(text):
        if quote is not None:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "=":
            return text[:i], "=", text[i + 1:]
    return text, "", ""


def _key_path(name: str) -> list[str] | None:
    """The parts of a TOML dotted key (``uncertainty.vary."contact.restitution"`` ->
    ``["uncertainty", "vary", "contact.restitution"]``), or None if it is none."""
    if not name.strip():
        return None
    if '"' not in name and "'" not in name:
        return [part.strip() for part in name.split(".")]
    try:
        node = tomllib.loads(f"{name} = 0")
    except (tomllib.TOMLDecodeError, ValueError, RecursionError):
        return None
    path = []
    while isinstance(node, dict) and len(node) == 1:
        (key, node), = node.items()
        path.append(key)
    return path


def with_settings(scene: Scene, settings: list[str], warn: bool = True) -> Scene:
    """``scene`` with the ``--set section.key=value`` settings applied, in order, each
    checked as the same key in the file would be (unknown keys with the did-you-mean,
    values with their range). ``warn``: a deprecated key's warning (a sweep's points: said
    once, by ``--vary``)."""
    data = copy.deepcopy(scene.raw)
    shape_before = (data.get("device") or {}).get("shape", "tube")
    set_device_keys = set()
    for text in settings:
        path, value = parse_setting(text)
        new = RENAMED_KEYS.get(tuple(path)) if len(path) == 2 else None
        if new is not None:   # the file's old names were warned about when it was read
            if launched_rank() == 0:   # under mpirun: one line, not one per rank
                warnings.warn(f"--set {path[0]}.{path[1]}: [{path[0]}] {path[1]} is now called "
                          f"{new}: write --set {path[0]}.{new}={value!r} ({path[1]} is "
                              "read until the next release)", FutureWarning, stacklevel=2)
            data[path[0]] = dict(data.get(path[0]) or {})
            update_section(data, path[0], {new: value})
            continue
        if tuple(path) == ("circuit", "parallel_capacitance_pF") and warn:   # deprecated
            from .model import warn_deprecated_capacitance
            warn_deprecated_capacitance(value, option="--set", stacklevel=3)
        node = data
        for part in path[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise SceneError(f"--set {text!r}: {part} is a value, not a table")
            node = child
        node[path[-1]] = value
        if path[0] == "device" and len(path) == 2:
            set_device_keys.add(path[1])
    shape = (data.get("device") or {}).get("shape", "tube")
    if isinstance(shape, str) and isinstance(data.get("device"), dict):
        # --set device.shape=...: the other shape's keys go (a file would not write them)
        data["device"] = switched_shape(data["device"], shape_before, shape, set_device_keys)
    base = Path(scene.source).parent if scene.source not in ("<default>", "<dict>") else None
    source = scene.source if scene.source != "<default>" else "<default scene>"
    from .plausible import warn_metres_for_mm
    warn_metres_for_mm(data, keys={tuple(parse_setting(t)[0]) for t in settings})
    before = scene
    scene = build(data, base_dir=base, source=f"{source} with --set", text="", warn=False,
                  settings=(*scene.settings, *settings))
    check_rules(scene, before)      # the rules between keys, as for the file
    return scene


def _check_nesting_text(text: str, source: str) -> None:
    """Refuse brackets nested deeper than a scene can use before tomllib recurses into
    them (a cheap upper bound: brackets inside strings and comments count too, so the
    text limit is generous, 4 x MAX_TOML_DEPTH)."""
    depth = deepest = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            if depth > deepest:
                deepest = depth
                if deepest > 4 * MAX_TOML_DEPTH:
                    raise SceneError(f"{source}: nested too deeply: allowed {MAX_TOML_DEPTH} "
                                     "levels of tables and arrays")
        elif ch in "]}":
            depth = max(0, depth - 1)


def _check_values(data, source: str, path: str = "", depth: int = 0) -> None:
    """Every value of a parsed scene: no TOML dates/times (no key takes one), nesting at
    most MAX_TOML_DEPTH, integers within the doubles."""
    if depth > MAX_TOML_DEPTH:
        raise SceneError(f"{source}: {path} is nested too deeply: allowed {MAX_TOML_DEPTH} "
                         "levels of tables and arrays")
    items = data.items() if isinstance(data, dict) else enumerate(data) \
        if isinstance(data, list) else ()
    for key, value in items:
        where = f"{path}.{key}" if isinstance(key, str) and path else \
            f"{path}[{key}]" if path else f"[{key}]"
        if isinstance(value, (datetime.date, datetime.time)):
            raise SceneError(f"{source}: {_where(where)} = {show(value)}: no scene key takes a "
                             "date or time; write a number or a string")
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 2**1023:
            raise SceneError(f"{source}: {_where(where)} = {show(value)} is out of range: "
                             "integers must stay within the doubles (|x| < 1.8e308)")
        if isinstance(value, (dict, list)):
            _check_values(value, source, where, depth + 1)


def _where(path: str) -> str:
    """``[run].duration_s`` -> ``[run] duration_s`` (how messages name scene keys)."""
    sec, dot, rest = path.partition("].")
    return f"{sec}] {rest}" if dot else path


def check_scene_argument(function: str, scene, name: str = "scene") -> Scene:
    """``scene`` is a :class:`Scene` (``function`` needs a whole scene): else one
    TypeError naming the function and the argument (issue #43.19)."""
    if not isinstance(scene, Scene):
        shown = repr(scene) if len(repr(scene)) <= 60 else repr(scene)[:57] + "..."
        raise TypeError(f"{function}({name}={shown}): expected a tengfield.Scene "
                        "(tengfield.default_scene(), tengfield.load_scene(path)), got "
                        f"{type(scene).__name__}")
    return scene


def verb_scene(function: str, scene) -> Scene:
    """The scene a verb taking a scene file's path was given (``tf.breakdown``,
    ``tf.sweep``): a :class:`Scene`, a path or ``None`` (the default scene), else one
    TypeError naming the verb (:func:`check_scene_argument`)."""
    if not isinstance(scene, (str, os.PathLike)) and scene is not None:
        check_scene_argument(function, scene)
    return load_scene(scene)


def as_scene(scene, function: str) -> Scene:
    """``scene`` itself, or the scene of a dict of sections (``{"excitation":
    {"frequency_hz": 30.0}, ...}``, file-level keys; the rest default); a
    :class:`TypeError` naming what to pass for anything else."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        from .model import _python_value
        data = {}
        for sec, values in scene.items():
            if not isinstance(values, dict):
                raise TypeError(f"tengfield.{function}({{{sec!r}: {values!r:.40}}}): each "
                                f"section of a scene dict is a dict of keys, e.g. "
                                f"{{'excitation': {{'frequency_hz': 30.0}}}}")
            data[sec] = {k: _python_value(v) for k, v in values.items()}
        return Scene.from_dict(data)
    shown = repr(scene) if len(repr(scene)) <= 60 else repr(scene)[:57] + "..."
    raise TypeError(f"tengfield.{function}(scene={shown}): expected a tengfield.Scene "
                    f"(tengfield.default_scene(), tengfield.load_scene(path)) or a dict of "
                    f"scene sections, got {type(scene).__name__}")
