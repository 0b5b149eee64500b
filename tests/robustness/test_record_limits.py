"""#30 items 16, 17: a CSV cell over Python's csv field limit and a smoothing cut-off far
below the record's span are one line each (were _csv.Error and LinAlgError tracebacks)."""
import numpy as np
import pytest

from tengfield.dynamics.table import recorded_table
from tengfield.errors import DynamicsError, SceneError
from tengfield.scene import load_scene
from tengfield.scene.recorded import read_table


def record_rows(n=50):
    return [f"{i * 1e-3},{1e-4 * (i % 5)}" for i in range(n)]


@pytest.mark.parametrize("where", ["signal", "unused", "header"])
def test_a_field_over_the_csv_limit_is_one_line(tmp_path, where):
    rows = record_rows()
    header = "time_s,z_m,note"
    rows = [r + ",x" for r in rows]
    if where == "signal":
        rows[3] = f"{3e-3},{'a' * 200_000},x"
    elif where == "unused":
        rows[3] = f"{3e-3},{1e-4},{'y' * 200_000}"
    else:
        header = "time_s,z_m," + "n" * 200_000
    (tmp_path / "t.csv").write_text(header + "\n" + "\n".join(rows) + "\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\n'
                                     'time_column = "time_s"\nsignal_column = "z_m"\n')
    if where == "unused":        # Arrow reads only the columns used: accepted
        excitation = load_scene(tmp_path / "s.toml").excitation
        assert len(excitation.times) == len(excitation.values) > 0
        return
    with pytest.raises(SceneError) as err:
        load_scene(tmp_path / "s.toml")
    line = 5 if where == "signal" else 1
    assert f"line {line} cannot be read as CSV (field larger than field limit" in str(err.value)
    assert len(str(err.value)) < 300


def test_a_field_over_the_limit_in_a_measured_trace(tmp_path):
    (tmp_path / "m.csv").write_text("time_s,v\n0," + "2" * 140_000 + "\n")
    with pytest.raises(SceneError, match="--measured: line 2 cannot be read as CSV"):
        read_table(str(tmp_path / "m.csv"), None, "--measured", max_bytes=10**7, max_rows=10)


@pytest.mark.parametrize("cutoff", [1e-6, 0.5])
def test_a_cut_off_below_one_over_the_records_span_is_refused(cutoff):
    t = np.arange(10_000) * 1e-4            # 1 s at 10 kHz
    z = 1e-3 * np.sin(2 * np.pi * 20 * t)
    with pytest.raises(DynamicsError, match=r"smoothing_hz = .*: allowed \[1\.0001, 5000\) Hz "
                                            r"\(from 1 / the record's duration 0\.9999 s"):
        recorded_table(t, z, "displacement", smoothing_hz=cutoff)


def test_a_cut_off_inside_the_range_smooths():
    t = np.arange(10_000) * 1e-4
    z = 1e-3 * np.sin(2 * np.pi * 20 * t)
    table = recorded_table(t, z, "displacement", smoothing_hz=1000.0)
    pos = table.evaluate(t[2000:8000])[0]
    assert np.max(np.abs(pos - z[2000:8000])) < 1e-6


# -- #30 item 18: a single-sample glitch in a displacement record ------------------------
def sine_record(noise=0.0):
    t = np.arange(10_000) * 1e-4
    z = 1.5e-3 * np.sin(2 * np.pi * 20 * t)
    if noise:
        z = z + np.random.default_rng(3).normal(0, noise, z.size)
    return t, z


def test_a_single_sample_glitch_is_named_by_its_row():
    t, z = sine_record()
    z[216] += 1e-4                         # 0.1 mm at t = 0.0216 s
    with pytest.raises(DynamicsError, match=r"displacement at data row 217 \(t = 0\.0216 s\) "
                                            r"is 0\.0001 m off its neighbours.*smoothing_hz"):
        recorded_table(t, z, "displacement")
    recorded_table(t, z, "displacement", smoothing_hz=1000.0)   # low-passed: accepted


@pytest.mark.parametrize("noise", [0.0, 1e-6, 2e-5])
def test_clean_and_noisy_records_and_kinks_pass(noise):
    t, z = sine_record(noise)
    recorded_table(t, z, "displacement")
    tri = 1e-3 * np.abs(((t * 20) % 1.0) - 0.5)          # a triangle wave: kinks, no spike
    recorded_table(t, tri, "displacement")
