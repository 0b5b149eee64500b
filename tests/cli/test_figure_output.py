"""``--dpi N`` and ``--figure-format png|pdf|svg``: every figure of a command at N dots
per inch and in that format, the ones drawn by the figure process included (issue #42:
figures for a paper); a bad value is one line naming the option, the value and what is
allowed, before any output exists."""
from __future__ import annotations

import pytest

from tengfield.plotting import DPI_RANGE

SCENE = "[run]\nduration_s = 0.3\nsettle_periods = 2\n"


def _size(path):
    from PIL import Image

    with Image.open(path) as image:
        return image.size


@pytest.mark.slow
def test_dpi_scales_every_figure_in_proportion(tmp_path, run_cli):
    (tmp_path / "s.toml").write_text(SCENE)
    sizes = {}
    for dpi in (60, 120):
        out = tmp_path / f"out{dpi}"
        proc = run_cli("dynamics", "s.toml", "-o", out, "--dpi", str(dpi), cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        sizes[dpi] = _size(out / "trajectory.png")
    assert sizes[120][0] == pytest.approx(2 * sizes[60][0], abs=2)
    assert sizes[120][1] == pytest.approx(2 * sizes[60][1], abs=2)


@pytest.mark.slow
@pytest.mark.parametrize("value", ["5", "1e9", "nan"])
def test_a_bad_dpi_is_one_line_and_writes_nothing(tmp_path, run_cli, value):
    (tmp_path / "s.toml").write_text(SCENE)
    proc = run_cli("dynamics", "s.toml", "-o", tmp_path / "out", "--dpi", value, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tengfield: error: --dpi "), proc.stderr
    assert f"allowed [{DPI_RANGE[0]:g}, {DPI_RANGE[1]:g}]" in lines[0]
    assert not (tmp_path / "out").exists()


def test_the_setting_reaches_save_figure(tmp_path):
    from tengfield import plotting

    fig = plotting.new_figure((2.0, 1.0))
    fig.subplots().plot([0, 1], [0, 1])
    try:
        plotting.set_figure_dpi(50)
        plotting.save_figure(fig, tmp_path / "a.png", 120)
    finally:
        plotting.set_figure_dpi(None)
    plotting.save_figure(fig, tmp_path / "b.png", 120)
    assert _size(tmp_path / "a.png") == (100, 50)
    assert _size(tmp_path / "b.png") == (240, 120)


COARSE = SCENE + "[field]\nmesh_size_mm = 1.5\ndegree = 1\ntolerance = 0.05\n"


@pytest.mark.slow
@pytest.mark.parametrize("fmt, magic", [("pdf", b"%PDF"), ("svg", b"<?xml")])
def test_every_figure_of_a_run_in_the_format_asked(tmp_path, run_cli, fmt, magic):
    (tmp_path / "s.toml").write_text(COARSE)
    out = tmp_path / "out"
    proc = run_cli("run", "s.toml", "-o", out, "--figure-format", fmt, "--cache-dir",
                   tmp_path / "cache", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    figures = sorted(p.name for p in out.glob(f"*.{fmt}"))
    assert {"waveforms", "surrogate", "trajectory"} <= {n.rsplit(".", 1)[0] for n in figures}
    assert not list(out.glob("*.png")), list(out.glob("*.png"))
    for name in figures:
        assert (out / name).read_bytes()[:5].startswith(magic), name
        assert str(out / name) in proc.stdout      # the "wrote" line names the file


@pytest.mark.slow
def test_an_unknown_format_is_one_line_and_writes_nothing(tmp_path, run_cli):
    (tmp_path / "s.toml").write_text(SCENE)
    proc = run_cli("dynamics", "s.toml", "-o", tmp_path / "out", "--figure-format", "jpg",
                   cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == ("tengfield: error: --figure-format 'jpg' is not offered: "
                                   "allowed png, pdf, svg"), proc.stderr
    assert not (tmp_path / "out").exists()


def test_figure_names_follow_the_format():
    from tengfield.files import figure_file, set_figure_format

    try:
        set_figure_format("PDF")
        assert figure_file("waveforms") == "waveforms.pdf"
    finally:
        set_figure_format("png")
    assert figure_file("waveforms") == "waveforms.png"
    with pytest.raises(ValueError, match="allowed png, pdf, svg"):
        set_figure_format("eps")


@pytest.mark.parametrize("fmt", ["pdf", "svg"])
def test_field_refuses_a_format_its_pyvista_figure_cannot_be(tmp_path, run_cli, fmt):
    """``field --figure-format pdf`` wrote field.png silently (issue #53): one line, before
    any work, naming the format and what to do; with --no-plots nothing is drawn, so it
    passes the check."""
    proc = run_cli("field", "--position-mm", "1.5", "--figure-format", fmt,
                   "-o", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        f"tengfield: error: --figure-format '{fmt}' is not offered by tengfield field: its "
        "figures are drawn by pyvista as png only (omit --figure-format, or --no-plots)")
    assert not (tmp_path / "out").exists()
    from types import SimpleNamespace
    from tengfield.cli import _apply_settings
    _apply_settings(SimpleNamespace(figure_format=fmt, figure_formats=("png",), no_plot=True,
                                    command="field", dpi=None, settings=[]))
    _apply_settings(SimpleNamespace(figure_format="png", dpi=None, settings=[]))
