"""The terminal topologies as a registry (issue #51): every entry of
``tengfield.terminals.TOPOLOGIES`` answers the consumers' questions consistently. Its
closed forms (C_T, Q_u0, the pair's share) are checked against the linear algebra of
the electrode charges Q = C V + q (open and shorted potentials), on random physical
capacitance matrices; charge is conserved in the floating pair."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from tengfield import terminals
from tengfield.terminals import REFERENCES, TOPOLOGIES, topology

PF = 1e-12


@st.composite
def cells(draw):
    """A two-electrode cell: Maxwell matrix (C_ll, C_uu > -C_lu > 0, each row's sum the
    electrode's capacitance to the environment, > 0), the induced charges of a ball of
    charge q_b (each of sign -q_b, together at most |q_b|), twice: the position and the
    reference state."""
    def state():
        mutual = draw(st.floats(0.01, 10.0)) * PF
        to_env = [draw(st.floats(0.01, 5.0)) * PF for _ in range(2)]   # > 0: a real cell
        C = np.array([[mutual + to_env[0], -mutual], [-mutual, mutual + to_env[1]]])
        split = draw(st.floats(0.0, 1.0))
        kept = draw(st.floats(0.5, 1.0))      # the rest of the image on the environment
        return C, split, kept

    q_b = draw(st.sampled_from([-1.0, 1.0])) * draw(st.floats(1e-12, 1e-8))
    (C, s, k), (C0, s0, k0) = state(), state()
    q = -q_b * k * np.array([s, 1.0 - s])
    q0 = -q_b * k0 * np.array([s0, 1.0 - s0])
    return C, q, C0, q0, q_b


@pytest.mark.parametrize("reference", REFERENCES)
@settings(max_examples=200, deadline=None)
@given(cell=cells())
def test_the_open_circuit_voltage_is_the_short_circuit_charge_over_c_t(reference, cell):
    """V_OC by the linear solve of the open electrodes (the field plot's and the
    breakdown's potentials) = (Q_u0(z) − Q_u0(ref)) / C_T (the surrogate's closed form)."""
    C, q, C0, q0, q_b = cell
    wiring = topology(reference)
    V = wiring.open_potentials(C, q, wiring.reference_charges(C0, q0, q_b))
    q_sc = terminals.upper_short_circuit_charge(C[0, 0], C[0, 1], C[1, 1], q[0], q[1], q_b,
                                                reference) \
        - terminals.upper_short_circuit_charge(C0[0, 0], C0[0, 1], C0[1, 1], q0[0], q0[1], q_b,
                                               reference)
    c_t = terminals.terminal_capacitance(C[0, 0], C[0, 1], C[1, 1], reference)
    assert c_t > 0.0
    scale = abs(q_b) / c_t
    assert V[0] - V[1] == pytest.approx(q_sc / c_t, rel=1e-9, abs=1e-12 * scale)


@pytest.mark.parametrize("reference", REFERENCES)
@settings(max_examples=200, deadline=None)
@given(cell=cells())
def test_the_shorted_state_holds_its_charges(reference, cell):
    """Shorted: the electrode charges C V + q at the topology's potentials give the
    upper electrode Q_u0, the floating pair keeps −q_b (ball + electrodes neutral: charge
    conserved), the grounded lower electrode sits at 0 V."""
    C, q, _, _, q_b = cell
    wiring = topology(reference)
    V = wiring.short_potentials(C[None], q[None], q_b)[0]
    Q = C @ V + q
    assert V[0] == pytest.approx(V[1], rel=1e-12, abs=0.0)
    assert Q[1] == pytest.approx(wiring.upper_short_charge(C[0, 0], C[0, 1], C[1, 1], q[0],
                                                           q[1], q_b), rel=1e-9, abs=1e-12 * abs(q_b))
    reference_state = wiring.reference_charges(C, q, q_b)
    np.testing.assert_allclose(reference_state, Q, rtol=1e-9, atol=1e-12 * abs(q_b))
    if wiring.grounded_lower:
        assert V[0] == 0.0
    else:
        assert Q.sum() == pytest.approx(-q_b, rel=1e-12)


@pytest.mark.parametrize("reference", REFERENCES)
@settings(max_examples=100, deadline=None)
@given(cell=cells(), extra=st.floats(-1e-9, 1e-9))
def test_the_upper_share_is_what_the_upper_electrode_takes_of_an_added_charge(reference, cell,
                                                                               extra):
    """k: a charge δ put on the shorted electrodes (the contact charge's bookkeeping,
    tengfield.source.terminal) raises Q_u0 by k δ; the floating pair's δ is the ball's
    −δ, the grounded lower electrode's comes from the ground (k = 0)."""
    C, q, _, _, q_b = cell
    wiring = topology(reference)
    args = (C[0, 0], C[0, 1], C[1, 1])
    before = wiring.upper_short_charge(*args, q[0], q[1], q_b)
    after = wiring.upper_short_charge(*args, q[0], q[1], q_b - extra)   # pair total + δ
    k = wiring.upper_share(*args)
    assert after - before == pytest.approx(k * extra if not wiring.grounded_lower else 0.0,
                                           rel=1e-6, abs=1e-15 * abs(q_b) + 1e-24)
    assert 0.0 <= float(k) <= 1.0


def test_the_registry_is_the_one_list_of_references():
    from tengfield.scene.schema import SCHEMA

    assert REFERENCES == ("floating", "grounded-lower")
    assert SCHEMA["circuit"]["reference"].check[1] == REFERENCES
    assert all(TOPOLOGIES[name].name == name for name in REFERENCES)
    with pytest.raises(ValueError, match=r"^reference = 'ground' is not allowed: choose one "
                                         r"of 'floating', 'grounded-lower'$"):
        topology("ground")


def test_the_closed_forms_are_vectorised_over_positions():
    rng = np.random.default_rng(4)
    n = 7
    mutual = rng.uniform(0.1, 2.0, n) * PF
    C_ll, C_uu = mutual + rng.uniform(0, 1, n) * PF, mutual + rng.uniform(0, 1, n) * PF
    q_l, q_u = rng.uniform(0, 1, n) * 1e-10, rng.uniform(0, 1, n) * 1e-10
    for reference in REFERENCES:
        c_t = terminals.terminal_capacitance(C_ll, -mutual, C_uu, reference)
        q_u0 = terminals.upper_short_circuit_charge(C_ll, -mutual, C_uu, q_l, q_u, -2e-10,
                                                    reference)
        assert c_t.shape == q_u0.shape == (n,)
        for i in range(n):
            assert c_t[i] == terminals.terminal_capacitance(C_ll[i], -mutual[i], C_uu[i],
                                                            reference)
