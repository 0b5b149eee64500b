"""Helpers shared by test files (imported by name: ``from helpers import mpi_env``); a
test file imports helpers from here or from the analytic stand-ins (``plate_model``,
``zr_model``), never from another test file."""
from __future__ import annotations

import math
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def mpi_env():
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1",
                MPLBACKEND="Agg",
                PYTHONPATH=os.pathsep.join(p for p in (str(ROOT / "src"),
                                                       os.environ.get("PYTHONPATH")) if p))


def needs_mpirun():
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")


def oversubscribed_env(cli_env, cache) -> dict:
    """The environment of a serial or ``mpirun -n 2`` CLI run (``cli_env``: the fixture),
    oversubscribed (the machine's 2 cores are shared with others), with its own cache
    directory ``cache``, outside any mpirun of the caller."""
    env = cli_env(OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
                  PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe",
                  TENGFIELD_CACHE_DIR=cache)
    env.pop("OMPI_COMM_WORLD_SIZE", None)
    return env


def serial_and_mpirun(cli_command, cli_env, tmp_path, *args, serial=(), timeout=600,
                      shared_cache=False):
    """``tengfield args... -o tmp_path/one`` (with ``serial``: its own further arguments)
    and ``mpirun -n 2 tengfield args... -o tmp_path/two``, each from an empty cache of
    its own (``shared_cache``: one cache, the mpirun run reading what the serial one
    wrote); both must exit 0. Skips without mpirun. Returns the two CompletedProcesses."""
    import subprocess

    needs_mpirun()
    caches = ("cache",) * 2 if shared_cache else ("cache-one", "cache-two")
    one = subprocess.run(cli_command(*args, "-o", tmp_path / "one", *serial),
                         capture_output=True, text=True, timeout=timeout,
                         env=oversubscribed_env(cli_env, tmp_path / caches[0]))
    assert one.returncode == 0, one.stderr[-3000:]
    two = subprocess.run([shutil.which("mpirun"), "-n", "2",
                          *cli_command(*args, "-o", tmp_path / "two")],
                         capture_output=True, text=True, timeout=timeout,
                         env=oversubscribed_env(cli_env, tmp_path / caches[1]))
    assert two.returncode == 0, two.stderr[-3000:]
    return one, two


def same_rows(a: list[dict], b: list[dict]) -> bool:
    """Row lists equal exactly (None and NaN compare equal to themselves)."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if x.keys() != y.keys():
            return False
        for k in x:
            u, v = x[k], y[k]
            if isinstance(u, float) and isinstance(v, float) and math.isnan(u) and math.isnan(v):
                continue
            if u != v:
                return False
    return True


def assert_png(path):
    """``path`` is a non-empty PNG that decodes to an image with content."""
    from PIL import Image

    assert path.stat().st_size > 0, path
    with Image.open(path) as image:
        assert image.format == "PNG"
        image.load()
        pixels = np.asarray(image.convert("L"))
    assert pixels.shape[0] > 100 and pixels.shape[1] > 100
    assert pixels.std() > 1.0, f"{path} is blank"


def quick_start_commands() -> list[str]:
    """The command lines of README's Quick start block (comments dropped)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"## Quick start\s*```bash\n(.*?)```", text, re.S).group(1)
    return [line.split("#")[0].strip() for line in block.splitlines() if line.split("#")[0].strip()]


def quick_start_script(lines: list[str]) -> str:
    """``lines`` as one bash script that stops at the first failing line."""
    return "set -e\n" + "\n".join(lines) + "\n"


#: a scene key written raw ("device.surface_charge_uC_per_m2", "contact.restitution")
_RAW_KEY = re.compile(r"\b(device|contact|excitation|circuit|instrument|run|field|initial|"
                      r"breakdown|array|design|uncertainty|peak|peak_to_peak|"
                      r"energy_per_cycle|load|rectifier)\.[a-z_0-9]+", re.I)
#: unit spellings of a terminal, not of a figure: the quantity table writes µ, ², ³, Ω
_ASCII_UNITS = re.compile(r"\b(uC|uW|uA|uJ|uF|nC/m\^2)\b|/m\^[23]|\bohm\b")
#: a terminal's caret power in a unit ("µW/cm^3"): a figure writes cm³ (mathtext aside)
_CARET_POWER = re.compile(r"[a-zµ]\^-?[0-9]")


def figure_texts(fig) -> list[str]:
    """Every piece of text of a matplotlib Figure: titles, axis and tick labels, legends,
    free text."""
    texts = [t.get_text() for t in fig.findobj(lambda o: hasattr(o, "get_text"))]
    return [t for t in texts if t and t.strip()]


def _names_its_axis(ax, axis: str, fig) -> bool:
    """An axis is labelled by its label, by category tick labels (a bar per input), or
    through an axes sharing it that carries the label (stacked panels)."""
    which = ax.xaxis if axis == "x" else ax.yaxis
    if which.get_label().get_text().strip():
        return True
    ticks = [t.get_text() for t in which.get_ticklabels() if t.get_text().strip()]
    numeric = re.compile(r"[−\-+0-9.,e×^${} ]*")     # 1.5, −2, 1e-3, $10^{-3}$
    if ticks and not all(numeric.fullmatch(t.replace("\\mathdefault", "")) for t in ticks):
        return True
    shared = ax.get_shared_x_axes() if axis == "x" else ax.get_shared_y_axes()
    return any(o is not ax and shared.joined(o, ax)
               and (o.xaxis if axis == "x" else o.yaxis).get_label().get_text().strip()
               for o in fig.axes)


def assert_labelled(fig) -> None:
    """A figure as a paper writes it (issue #42): every axes that draws data names both
    axes, no raw ``section.key`` names, no "cell(s)", units in the quantity table's style
    (µC/m², µW, Ω)."""
    for ax in fig.axes:
        has_data = bool(ax.lines or ax.collections or ax.patches or ax.images)
        if has_data and ax.get_visible() and ax.axison:
            for axis in "xy":
                assert _names_its_axis(ax, axis, fig), \
                    f"an unlabelled {axis} axis (title {ax.get_title()!r})"
    for text in figure_texts(fig):
        assert not _RAW_KEY.search(text), f"a raw scene key in {text!r}"
        assert "cell(s)" not in text, text
        assert not _ASCII_UNITS.search(text), f"an ASCII unit in {text!r}"
        assert "$" in text or not _CARET_POWER.search(text), f"a caret power in {text!r}"
    assert_no_offsets(fig)
    assert_legends_clear(fig)


def _drawn(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def _line_points(ax):
    """Display coordinates of the data vertices of ``ax``'s lines and markers (reference
    lines such as axhline left out)."""
    points = []
    for line in ax.get_lines():
        if line.get_transform() is ax.transData and line.get_visible():
            xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
            points.append(ax.transData.transform(xy[np.all(np.isfinite(xy), axis=1)]))
    for coll in ax.collections:
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if offsets.size and coll.get_offset_transform() is ax.transData and len(offsets) > 1:
            points.append(ax.transData.transform(offsets))
    return np.concatenate(points) if points else np.empty((0, 2))


def assert_no_offsets(fig) -> None:
    """No axis carries an offset or scale text ("1e−6+1.2556572e3", "1e−6" over a J axis):
    the unit in its label is then not the unit of its ticks, and a quantity constant to
    rounding would be drawn as a trend. Equal tick labels (a constant drawn at too many
    digits) fail too."""
    _drawn(fig)
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            offset = axis.get_offset_text().get_text()
            assert not offset.strip(), \
                f"{name} axis of {ax.get_title() or ax.get_ylabel()!r} has the offset {offset!r}"
            ticks = [t.get_text() for t in axis.get_ticklabels() if t.get_text().strip()]
            assert len(set(ticks)) == len(ticks), f"{name} axis repeats tick labels {ticks}"


def assert_legends_clear(fig) -> None:
    """No legend inside an axes covers a data point of it (lines' vertices, markers)."""
    renderer = _drawn(fig)
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None or not legend.get_visible():
            continue
        box = legend.get_window_extent(renderer)
        xy = _line_points(ax)
        inside = ((xy[:, 0] > box.x0 + 1) & (xy[:, 0] < box.x1 - 1)
                  & (xy[:, 1] > box.y0 + 1) & (xy[:, 1] < box.y1 - 1))
        assert not np.any(inside), \
            f"the legend of {ax.get_title() or ax.get_ylabel()!r} covers {int(inside.sum())} data points"


#: a number and its unit on a terminal line: "I_SC = 56.87 nA", "E = 3.4 µJ"
_TERMINAL_VALUE = r"{symbol}\b[^,;\n]*?[−\-+]?[0-9][0-9.]*(?:e[−\-+]?[0-9]+)? ([^\s,;:()]+)"


def assert_units_as_terminal(fig, lines) -> None:
    """Each axis label "SYMBOL ... [unit]" whose symbol the terminal ``lines`` print with
    a unit ("I_SC peak [nA]: ..." or "I_SC = 56.87 nA") uses the terminal's unit (µJ on
    both, not J on the figure)."""
    text = "\n".join(lines)
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            m = re.match(r"(\S+).*\[([^\]]+)\]\s*$", label)
            if not m:
                continue
            symbol = re.escape(m.group(1))
            said = (re.search(rf"(?m)^\s*{symbol}\b[^\n\[:]*\[([^\]]+)\]", text)
                    or re.search(_TERMINAL_VALUE.format(symbol=symbol), text))
            if said:
                assert said.group(1).replace("^2", "²") == m.group(2), \
                    f"{label!r}: the terminal says {said.group(0)!r}"


def assert_tables_agree_within_estimates(table, reference) -> np.ndarray:
    """Two surrogate tables of one geometry (moved or mapped meshes against remeshed
    ones) agree at every position: the largest relative change of C and q is within
    both tables' field error estimates there. Returns the changes."""
    np.testing.assert_allclose(table.positions, reference.positions, rtol=0, atol=1e-15)
    n = len(reference.positions)
    scale_c = np.abs(reference.capacitance).reshape(n, -1).max(axis=1)
    scale_q = np.abs(reference.induced_fraction).max(axis=1)
    change = np.maximum(
        np.abs(table.capacitance - reference.capacitance).reshape(n, -1).max(axis=1) / scale_c,
        np.abs(table.induced_fraction - reference.induced_fraction).max(axis=1) / scale_q)
    bound = np.minimum(table.field_error, reference.field_error)
    assert np.all(change <= bound), (change, bound)
    return change


def single_and_pair_runs(run_cli, tmp_path, scene_text, *, timeout=900):
    """``tengfield run`` (figures on, one cache) of the single-electrode cell and of the
    pair: ``scene_text(extra)`` is the scene file with ``extra`` the ``[device]`` line
    (``electrodes = "lower"`` or nothing); both must exit 0. Returns ``(single summary,
    pair summary, the single run's output directory, its CompletedProcess)``."""
    import json

    runs = {}
    for name, extra in (("single", 'electrodes = "lower"'), ("pair", "")):
        scene = tmp_path / f"{name}.toml"
        scene.write_text(scene_text(extra))
        out = tmp_path / name
        proc = run_cli("run", scene, "-o", out, "--cache-dir", tmp_path / "cache",
                       timeout=timeout)
        assert proc.returncode == 0, proc.stderr[-2000:]
        runs[name] = (json.loads((out / "summary.json").read_text()), out, proc)
    (single, out, proc), (pair, _, _) = runs["single"], runs["pair"]
    assert single["reference"] == "lower-to-ground" and pair["reference"] == "floating"
    return single, pair, out, proc
