"""#43 item 15: ``--reference`` values are checked: a non-positive, denormal or tiny value
(``Q_pp_nC=1e-300``, ``5e-324``: silently dropped; ``V_pp_V=0``: the "not given" value) and
a key given twice are refused in one line before any work; a large difference in % is
printed in a few digits, never 300."""
from __future__ import annotations

import pytest

from tengfield.cli import main
from tengfield.commands.run import comparison_lines


@pytest.mark.parametrize("items, needle", [
    (["Q_pp_nC=1e-300"], "Q_pp_nC = 1e-300 is out of range: allowed [1e-12, 1e+30] nC"),
    (["Q_pp_nC=5e-324"], "Q_pp_nC = 5e-324 is out of range"),
    (["V_pp_V=0"], "V_pp_V = 0 is out of range"),
    (["V_pp_V=-4.2"], "V_pp_V = -4.2 is out of range"),
    (["I_pp_uA=nan"], "I_pp_uA = nan is out of range"),
    (["V_pp_V=4.2", "V_pp_V=5"], "V_pp_V is given twice (4.2 and 5): allowed once"),
])
def test_bad_reference_values_are_one_line_before_the_run(tmp_path, capsys, items, needle):
    out = tmp_path / "out"
    assert main(["run", "--no-plots", "--reference", *items, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err, err
    assert not out.exists()


def test_a_large_difference_is_a_few_digits():
    row = {"measured_value": 1e-12, "unit": "nC", "tool_value": 1.0,
           "difference_percent": 1e14 - 100.0, "tool_key": "peak_to_peak.Q_sc_C",
           "tool_label": "Q_SC"}
    huge = dict(row, measured_value=1e-300, difference_percent=1e302)
    lines = comparison_lines({"measured_comparison": {"quantities": {"Q_pp_nC": row,
                                                                     "Q_peak_nC": huge}}})
    assert "+1e+14 %" in lines[1] and "+1e+302 %" in lines[2], lines
    assert max(map(len, lines)) < 200
    small = comparison_lines({"measured_comparison": {"quantities": {
        "Q_pp_nC": dict(row, difference_percent=-12.34)}}})
    assert "-12.3 %" in small[1]


@pytest.mark.parametrize("value", ["5e-324", "1e-300"])
def test_a_tiny_value_in_the_file_is_refused_not_dropped(tmp_path, capsys, value):
    """In the file too: 5e-324 nC is 0 C, which meant "not given" (dropped silently)."""
    path = tmp_path / "ref.toml"
    path.write_text(f"[reference]\nQ_pp_nC = {value}\n")
    assert main(["scene", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"[reference] Q_pp_nC = {value} is out of range" in err, err
