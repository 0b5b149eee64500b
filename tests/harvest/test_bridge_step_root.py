"""vq.png of a Shockley bridge spiked to ±1.6 V (issue #53; ngspice on the same bridge
stays within −0.57…0.51 V): one transfer step returned the blocked-move voltage as its
root. The safeguarded Newton of ``_cell_after`` stopped on a tiny step where the path law's
slope is huge (i_A ≈ −I_s at no transfer), with a residual of volts. Each step's V' solves
C (v − V') = h [i(V' − U) − i(−V' − U)], and the terminal stays within U + 2 V_D(I)."""
import numpy as np
import pytest

from tengfield.harvest import Diode
from tengfield.harvest._kernel import _cell_after, _path_current

SHOCKLEY = 1


@pytest.mark.parametrize("v", [0.45, 0.9, 1.2, 1.615, 2.0, -1.615, 3.0])
def test_the_step_voltage_solves_the_cells_charge_balance(v):
    """The step the spike came from (C = 0.313 pF, h = 0.2 ms, U = 19 µV: v = 1.615 V
    after the blocked move) and others around it."""
    diode = Diode(model="shockley")
    args = (SHOCKLEY, diode.forward_voltage, diode.saturation_current,
            diode.emission_coefficient * diode.thermal_voltage, diode.series_resistance)
    c, u, h = 3.1345e-13, 1.87e-5, 2.0e-4
    va = _cell_after(v, c, u, h, *args)
    flow = h * (_path_current(va - u, *args) - _path_current(-va - u, *args))
    assert c * (v - va) == pytest.approx(flow, rel=1e-6, abs=1e-22)
    assert abs(va) <= abs(v)                       # a bridge only takes charge away
    # the charge moved over h at most C v: its current within what 2 diodes pass at |V'|
    assert abs(va) < 0.7, va
