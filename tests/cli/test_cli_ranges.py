"""START:STOP:N ranges of `tengfield map` and `tengfield sweep` (one parser)."""
import numpy as np
import pytest

from tengfield.commands._ranges import parse_range
from tengfield.errors import SceneError


def test_linear_log_and_single_values():
    assert parse_range("5:70:14", "--f").tolist() == pytest.approx(np.linspace(5, 70, 14).tolist())
    assert parse_range("1e6:1e10:5", "--r", log=True).tolist() == pytest.approx(
        [1e6, 1e7, 1e8, 1e9, 1e10])
    assert parse_range("1.5", "--a").tolist() == [1.5]
    assert parse_range("0:3:4", "--a", positive=False).tolist() == [0.0, 1.0, 2.0, 3.0]


@pytest.mark.parametrize("text,kw,needle", [
    ("5:70", {}, "expected START:STOP:N"),
    ("a:b:3", {}, "must be numbers"),
    ("5:70:0", {}, "N = 0 is out of range"),
    ("5:70:200000", {}, "allowed [1, 100000]"),
    ("5:inf:3", {}, "finite"),
    ("-5:70:3", {}, "> 0"),
    ("0:3:4", {}, "> 0"),
    ("-1:3:4", {"positive": False}, ">= 0"),
    ("0:1e9:3", {"log": True, "positive": False}, "> 0"),
])
def test_bad_ranges_name_option_text_and_allowed(text, kw, needle):
    with pytest.raises(SceneError) as info:
        parse_range(text, "--frequency-hz", **kw)
    assert "--frequency-hz" in str(info.value) and repr(text) in str(info.value)
    assert needle in str(info.value)


def test_a_bad_sweep_point_is_refused_before_the_surrogate(tmp_path, capsys, monkeypatch):
    """0.0001 Hz: the run extended to a steady window (20 periods, 2e5 s at 20 kHz) is
    more samples than allowed: the sweep names the point and exits 2 before computing
    (or even looking for) a surrogate."""
    from tengfield.cli import main

    cache = tmp_path / "cache"
    monkeypatch.setenv("TENGFIELD_CACHE_DIR", str(cache))
    out = tmp_path / "out"
    assert main(["sweep", "--frequency-hz", "20:0.0001:2", "--amplitude-mm", "1", "-o",
                 str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("tengfield: error: sweep point frequency_hz = 0.0001, "
                             "amplitude_mm = 1: [run] duration_s x sample_rate_hz")
    assert not cache.exists() and not out.exists()


def test_sweep_library_names_the_bad_point():
    from tengfield.scene import default_scene
    from tengfield.sweeps import check_grid

    check_grid(default_scene(), [20.0, 30.0], [1e-3])
    with pytest.raises(SceneError, match=r"sweep point frequency_hz = 0.0001, amplitude_mm = 1: "
                                         r"\[run\] duration_s x sample_rate_hz"):
        check_grid(default_scene(), [20.0, 1e-4], [1e-3, 2e-3])


def test_sweep_extends_the_run_where_settling_leaves_no_window():
    """The README's sweep from 5 Hz: the default 1 s run settles for 10 periods (2 s at
    5 Hz). Those points run settle_periods + 10 periods (10 = the steady periods the
    scene has at its own 20 Hz), the others keep duration_s; one line says which."""
    from tengfield.scene import default_scene
    from tengfield.sweeps import check_grid, extension_line, point_scene

    scene = default_scene()
    check_grid(scene, [5.0, 50.0], [0.5e-3, 3e-3])          # refused before this change
    for f in (5.0, 10.0):
        point = point_scene(scene, f, 1e-3)
        assert point.run.duration == pytest.approx(20 / f)
        assert point.excitation.frequency == f and point.excitation.amplitude == 1e-3
        steady = point.run.duration - point.run.settle_periods / f
        assert steady * f == pytest.approx(10)
    for f in (10.5, 20.0, 50.0):
        assert point_scene(scene, f, 1e-3).run.duration == scene.run.duration
    line = extension_line(scene, [5.0, 10.0, 15.0, 50.0])
    assert "\n" not in line and "frequency_hz <= 10:" in line and "those 2 frequencies" in line
    assert "settle_periods + 10 periods (up to 4 s)" in line
    assert extension_line(scene, [15.0, 50.0]) is None
