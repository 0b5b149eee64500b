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
    """10 Hz leaves no steady window in the default 1 s run (10 settle periods): the sweep
    names the point and exits 2 before computing (or even looking for) a surrogate."""
    from tengfield.cli import main

    cache = tmp_path / "cache"
    monkeypatch.setenv("TENGFIELD_CACHE_DIR", str(cache))
    out = tmp_path / "out"
    assert main(["sweep", "--frequency-hz", "20:10:2", "--amplitude-mm", "1", "-o",
                 str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("tengfield: error: sweep point frequency_hz = 10, amplitude_mm = 1: "
                             "[run] settle_periods = 10 leaves no steady window")
    assert not cache.exists() and not out.exists()


def test_sweep_library_names_the_bad_point():
    from tengfield.scene import default_scene
    from tengfield.sweep import check_grid

    check_grid(default_scene(), [20.0, 30.0], [1e-3])
    with pytest.raises(SceneError, match=r"sweep point frequency_hz = 10, amplitude_mm = 1: "
                                         r"\[run\] settle_periods"):
        check_grid(default_scene(), [20.0, 10.0], [1e-3, 2e-3])
