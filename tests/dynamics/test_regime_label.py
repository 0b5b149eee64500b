"""How regimes are said (issue #29): an aperiodic regime is "chaos (aperiodic)", never
"chaos, period 0"; `tengfield map` prints a table of regimes, not a Python dict."""
from __future__ import annotations

import re

from tengfield.cli import main
from tengfield.dynamics.regime import regime_label, regime_table
from tengfield.dynamics.result import REGIMES

#: 20 Hz, 5 mm, e = 0.5 on the default device: aperiodic over every run up to 400 periods
#: (25 Hz, 3 mm, e = 0.9, aperiodic over a 4 s run, settles to period 1 by 8 s: #42)
CHAOS = ("[excitation]\nfrequency_hz = 20.0\namplitude_mm = 5.0\n[contact]\nrestitution = 0.5\n"
         "[run]\nduration_s = 4.0\nsample_rate_hz = 2000.0\n")


def test_labels():
    assert regime_label("chaos", 0) == "chaos (aperiodic)"
    assert regime_label("bounce", 2) == "bounce, period 2"
    assert regime_label("regular-contact", 1) == "regular-contact, period 1"
    assert regime_label("rest", 1) == "rest"


def test_dynamics_says_chaos_is_aperiodic(tmp_path, capsys):
    (tmp_path / "chaos.toml").write_text(CHAOS)
    assert main(["dynamics", str(tmp_path / "chaos.toml"), "--no-plots",
                 "-o", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "regime chaos (aperiodic), over a run of " in out and "period 0" not in out


def test_map_prints_a_table(tmp_path, capsys):
    assert main(["map", "--frequency-hz", "10:40:3", "--amplitude-mm", "0.5:3:2",
                 "--periods", "40", "--jobs", "1", "--no-plots",
                 "-o", str(tmp_path / "map")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert "{" not in "\n".join(lines) and "}" not in "\n".join(lines)
    assert lines[0].startswith("6 points: ")
    assert lines[1].split() == ["regime", "points", "share"]
    rows = [ln.split() for ln in lines[2:]]
    assert all(r[0] in REGIMES and re.fullmatch(r"\d+(\.\d)?%", r[2]) for r in rows)
    assert sum(int(r[1]) for r in rows) == 6


def test_table_order_and_shares():
    table = regime_table({"chaos": 1, "bounce": 3}, REGIMES).splitlines()
    assert [ln.split()[0] for ln in table[1:]] == ["bounce", "chaos"]
    assert table[1].split()[1:] == ["3", "75.0%"]
