"""#30 items 19, 20 (files named by a scene): a relative name stays inside the scene's
folder (no ``..`` or symlink out of it), no error prints the file's content, and a
directory, FIFO or device is named as what it is, not "no such file"."""
import os

import numpy as np

import pytest

from tengfield.errors import SceneError
from tengfield.scene import load_scene

SECRET = "root:$6$saltsalt$hashhashhash:20228:0:99999:7:::\n"


def scene_in(folder, line):
    folder.mkdir(exist_ok=True)
    path = folder / "s.toml"
    path.write_text(f'[excitation]\nkind = "recorded"\n{line}\n')
    return path


@pytest.mark.parametrize("key", ["file", "psd_file"])
def test_a_relative_name_cannot_leave_the_scenes_folder(tmp_path, key):
    (tmp_path / "shadow").write_text(SECRET)
    path = scene_in(tmp_path / "a", f'{key} = "../shadow"')
    if key == "psd_file":
        path.write_text('[excitation]\nkind = "random"\npsd_file = "../shadow"\n')
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert "leads outside the scene's folder" in str(err.value)
    assert "hashhash" not in str(err.value) and "20228" not in str(err.value)


def test_a_symlink_out_of_the_folder_is_refused(tmp_path):
    (tmp_path / "shadow").write_text(SECRET)
    path = scene_in(tmp_path / "a", 'file = "link.csv"')
    (tmp_path / "a" / "link.csv").symlink_to(tmp_path / "shadow")
    with pytest.raises(SceneError, match="leads outside the scene's folder"):
        load_scene(path)


def test_a_file_in_a_subfolder_is_read(tmp_path):
    path = scene_in(tmp_path / "a", 'file = "data/t.csv"\ntime_column = "time_s"\nsignal_column = "z_m"')
    (tmp_path / "a" / "data").mkdir()
    rows = "\n".join(f"{i * 1e-3},{1e-3 * (i % 7)}" for i in range(200))
    (tmp_path / "a" / "data" / "t.csv").write_text("time_s,z_m\n" + rows + "\n")
    excitation = load_scene(path).excitation
    np.testing.assert_allclose(excitation.times, 1e-3 * np.arange(200))
    np.testing.assert_allclose(excitation.values, 1e-3 * (np.arange(200) % 7))


@pytest.mark.parametrize("kind", ["directory", "fifo", "device"])
def test_a_special_file_is_named_as_such(tmp_path, kind):
    target = tmp_path / "a" / "x.csv"
    path = scene_in(tmp_path / "a", 'file = "x.csv"' if kind != "device" else 'file = "/dev/zero"')
    if kind == "directory":
        target.mkdir()
    elif kind == "fifo":
        os.mkfifo(target)
    expected = {"directory": "is a directory", "fifo": "is a named pipe (FIFO)",
                "device": "is a character device"}[kind]
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert expected in str(err.value) and "no such file" not in str(err.value)


def write_record(folder, times):
    z = 1.5e-3 * np.sin(2 * np.pi * 20 * times)
    (folder / "t.csv").write_text("time_s,z_m\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(times, z)))
    path = folder / "s.toml"
    path.write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\ntime_column = "time_s"\n'
                    'signal_column = "z_m"\nsignal = "displacement"\nfrequency_hz = 20\n')
    return path


def test_a_gap_in_a_recorded_trace_is_refused_naming_the_rows(tmp_path):
    """#30 item 4: rows between 0.4 and 0.6 s removed (1000 x the median step) would be
    filled with invented motion: refused, naming the rows on both sides."""
    t = np.arange(0, 1.0, 2e-4)
    t = t[(t < 0.4) | (t > 0.6)]
    with pytest.raises(SceneError, match=r"a gap between data rows 2000 and 2001 \(0\.3998 s "
                                         r"then 0\.6002 s: 1e\+03 x the median step"):
        load_scene(write_record(tmp_path, t))


def test_a_few_missing_samples_are_interpolated(tmp_path):
    """Two missing samples (3 x the median step) are within the limit: read."""
    t = np.delete(np.arange(0, 0.5, 2e-4), [100, 101])
    excitation = load_scene(write_record(tmp_path, t)).excitation
    assert len(excitation.times) == len(t)
    assert np.diff(excitation.times).max() == pytest.approx(3 * 2e-4)


# -- #30 item 9: the recorded CSV is read column by column, in blocks ----------------------
def wide_record(folder, rows, comment=False):
    import pyarrow as pa
    import pyarrow.csv as pa_csv

    t = np.arange(rows) * 1e-4
    cols = {"time_s": t, "z_m": 1.5e-3 * np.sin(2 * np.pi * 20 * t)}
    cols.update({f"c{k}": np.round(np.random.default_rng(k).random(rows), 2) for k in range(28)})
    pa_csv.write_csv(pa.table(cols), folder / "t.csv")
    if comment:
        text = (folder / "t.csv").read_text()
        (folder / "t.csv").write_text("# a scope's export\n" + text)
    path = folder / "s.toml"
    path.write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\ntime_column = "time_s"\n'
                    'signal_column = "z_m"\nsignal = "displacement"\nfrequency_hz = 20\n')
    return path, cols


@pytest.mark.slow
def test_a_wide_record_is_read_in_little_memory(tmp_path):
    """30 columns, 200k rows: Python's memory while reading stays below 4x the file
    (Python's csv module kept every cell as a str: ~20x)."""
    import tracemalloc

    path, cols = wide_record(tmp_path, 200_000)
    size = (tmp_path / "t.csv").stat().st_size
    tracemalloc.start()
    try:
        scene = load_scene(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4 * size, (peak, size)
    np.testing.assert_array_equal(scene.excitation.times, cols["time_s"])
    np.testing.assert_array_equal(scene.excitation.values, cols["z_m"])


def test_the_block_reader_and_the_line_reader_agree(tmp_path):
    """A file with a comment goes through Python's reader: the same numbers."""
    path, cols = wide_record(tmp_path, 3000)
    fast = load_scene(path).excitation
    (tmp_path / "b").mkdir()
    path_b, _ = wide_record(tmp_path / "b", 3000, comment=True)
    slow = load_scene(path_b).excitation
    np.testing.assert_array_equal(fast.times, slow.times)
    np.testing.assert_array_equal(fast.values, slow.values)


# -- #30 item 22: what is not a plain number, and a header naming a column twice ------------
@pytest.mark.parametrize("cell", ["1_5e-4", "\u0661\u0662", "\uff11"])
def test_a_cell_float_would_take_is_refused(tmp_path, cell):
    rows = [f"{i * 1e-3},{1e-4 * (i % 5)}" for i in range(50)]
    rows[7] = f"{7e-3},{cell}"
    (tmp_path / "t.csv").write_text("time_s,z_m\n" + "\n".join(rows) + "\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\n'
                                     'time_column = "time_s"\nsignal_column = "z_m"\n')
    with pytest.raises(SceneError, match=r"column 'z_m' holds .* at line 9 \(data row 8\): "
                                         "expected a number"):
        load_scene(tmp_path / "s.toml")


def test_a_header_naming_a_column_twice_is_refused(tmp_path):
    rows = [f"{i * 1e-3},{1e-4 * (i % 5)},0" for i in range(50)]
    (tmp_path / "t.csv").write_text("time_s,z_m,z_m\n" + "\n".join(rows) + "\n")
    (tmp_path / "s.toml").write_text('[excitation]\nkind = "recorded"\nfile = "t.csv"\n'
                                     'time_column = "time_s"\nsignal_column = "z_m"\n')
    with pytest.raises(SceneError, match=r"names one column twice \(columns 2 and 3\)"):
        load_scene(tmp_path / "s.toml")
