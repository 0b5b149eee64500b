"""demos/fit_paper.py in --fast mode: the fit reproduces the hand reconciliation."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

DEMOS = Path(__file__).resolve().parents[2] / "demos"

pytestmark = [pytest.mark.field, pytest.mark.slow]   # a coarse dolfinx surrogate, ~15 s


def test_fit_paper_matches_the_hand_reconciliation(tmp_path, monkeypatch):
    pytest.importorskip("dolfinx")
    monkeypatch.syspath_prepend(str(DEMOS))
    monkeypatch.setattr(sys, "argv", ["fit_paper.py"])
    import electrical_common
    import fit_paper

    numbers = fit_paper.main(["--fast", "-o", str(tmp_path), "--cache-dir", str(tmp_path)])
    # the hand computation of docs/demos.md on the same surrogate
    _, curves = electrical_common.surrogate_curves(electrical_common.paper_scene(True),
                                                   str(tmp_path))
    scale, c_p = electrical_common.reconcile(curves, True)
    a = numbers["A"]
    assert a["values"]["surface_charge_uC_per_m2"] == pytest.approx(-8.0 * scale, rel=0.01)
    assert a["values"]["parallel_capacitance_pF"] == pytest.approx(c_p * 1e12, rel=0.01)
    # 5 % readings -> about 5 % standard error on sigma
    assert 0.02 < a["standard_errors"]["surface_charge_uC_per_m2"] / 35.8 < 0.1
    # the current reading does not fit with the other two: chi^2 says so
    assert numbers["B"]["chi2_reduced"] > 4.0
    assert any("not consistent" in n for n in numbers["B"]["notes"])
    # in the bouncing regime the ball sticks and lifts off at a fixed phase: e has no effect
    assert not numbers["C"]["identifiable"]["restitution"]
    for case in "ABC":
        assert (tmp_path / f"fit_paper_{case}" / "fit.png").exists()
