"""The one CSV writer of the dynamics files (tengfield.io.write_csv, Arrow): every double
comes back bit for bit, integers and strings as they are, a plain header; bad input is
refused before the file is touched."""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tengfield.io import write_csv

doubles = hnp.arrays(np.float64, st.integers(1, 200),
                     elements=st.floats(allow_nan=True, allow_infinity=True, width=64))


def _read(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def _same_double(text: str, value: float) -> bool:
    if math.isnan(value):
        return text == ""          # a missing value: an empty cell
    back = float(text)
    return back == value and math.copysign(1.0, back) == math.copysign(1.0, value)


@settings(max_examples=60, deadline=None)
@given(values=doubles)
def test_every_double_round_trips_bit_for_bit(tmp_path_factory, values):
    """Subnormals, -0.0, huge and tiny magnitudes, inf: float(text) is the double; NaN is
    an empty cell."""
    path = tmp_path_factory.mktemp("csv") / "x.csv"
    write_csv(path, ["x_m", "minus_x_m"], [values, -values])
    rows = _read(path)
    assert rows[0] == ["x_m", "minus_x_m"]
    assert len(rows) == values.size + 1
    for row, x in zip(rows[1:], values.tolist()):
        assert _same_double(row[0], x), (row[0], x)
        assert _same_double(row[1], -x), (row[1], -x)


def test_shortest_decimal_for_ordinary_numbers(tmp_path):
    """The shortest text that gives the double back (what a person reads in a spreadsheet)."""
    path = write_csv(tmp_path / "t.csv", ["time_s"], [np.array([0.0, 0.01, 0.1 + 0.2, 1 / 3])])
    assert [r[0] for r in _read(path)[1:]] == ["0", "0.01", "0.30000000000000004",
                                               "0.3333333333333333"]


def test_integers_strings_and_booleans(tmp_path):
    path = write_csv(tmp_path / "c.csv", ["surface", "steps", "initial_rest", "speed_m_per_s"],
                     [["lower", "upper", "wall"], np.array([3, 0, 12]),
                      np.array([True, False, True]), np.array([0.5, -1.25, 2.0])])
    assert _read(path) == [["surface", "steps", "initial_rest", "speed_m_per_s"],
                           ["lower", "3", "1", "0.5"], ["upper", "0", "0", "-1.25"],
                           ["wall", "12", "1", "2"]]


def test_nan_is_an_empty_cell_in_both_writers(tmp_path):
    """A value that does not exist (a contact still open at the run's end) is the empty
    cell spreadsheets, Origin and pandas read as missing, never the text 'nan'."""
    values = np.array([1.5, np.nan, -np.inf])
    plain = write_csv(tmp_path / "p.csv", ["a_s", "b"], [values, np.array([1, 2, 3])])
    printf = write_csv(tmp_path / "f.csv", ["a_s", "b"], [values, np.array([1, 2, 3])],
                       formats={"a_s": "%.10g"})
    assert _read(plain)[1:] == [["1.5", "1"], ["", "2"], ["-inf", "3"]]
    assert _read(printf)[1:] == [["1.5", "1"], ["", "2"], ["-inf", "3"]]
    back = np.genfromtxt(plain, delimiter=",", skip_header=1)
    assert np.isnan(back[1, 0]) and back[2, 0] == -np.inf


def test_empty_columns_give_the_header_only(tmp_path):
    path = write_csv(tmp_path / "e.csv", ["time_s", "plate"], [np.zeros(0), np.array([], str)])
    assert path.read_text() == "time_s,plate\n"


def test_columns_of_unequal_length_are_refused_before_writing(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("kept\n")
    with pytest.raises(ValueError, match="'b' has 2 rows"):
        write_csv(path, ["a", "b"], [np.zeros(3), np.zeros(2)])
    assert path.read_text() == "kept\n"


def test_header_and_columns_must_pair_up(tmp_path):
    with pytest.raises(ValueError):
        write_csv(tmp_path / "h.csv", ["a", "b"], [np.zeros(3)])


def test_a_write_error_names_the_file():
    """Arrow's own message ("Error writing bytes to file. Detail: [errno 28] ...")
    becomes the OSError a user reads: errno, its text and the path."""
    import errno

    with pytest.raises(OSError) as info:
        write_csv("/dev/full", ["x"], [np.arange(1e5)])
    assert info.value.errno == errno.ENOSPC
    assert info.value.strerror == "No space left on device"
    assert info.value.filename == "/dev/full"
