"""The device as a two-terminal source along one run (:class:`tengfield.source.Source`,
issue #51): the one place the terminal quantities come from. Its chunks are its whole
record bit for bit at any chunk size; V_OC = Q_SC / C_T and V_read = Q_SC / (C_T + C_p);
I_SC is the time derivative of Q_SC between impacts; N cells in parallel are N times one;
its ``state`` is its rows' (Q_SC, C_T); nothing charged gives zeros and an unknown C_T;
a contact-charged ball's source follows its charge history. The field is the analytic
plate model (no dolfinx)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import tengfield as tf
from tengfield import electrical
from tengfield.source import QUANTITIES, Source

import plate_model as fx

RUN = {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 20000.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("surrogates")


@pytest.fixture(scope="module")
def result(cache):
    scene = fx.scene_with(run=RUN, circuit={"parallel_capacitance_pF": 50.0})
    return tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)


def test_the_run_reads_its_columns_from_the_source(result):
    """waveforms.csv's terminal columns are the source's rows, bit for bit."""
    rows = Source.of_scene(result.scene, result.curves, result.dynamics).rows()
    for key, column in [("V_oc", "V_oc_V"), ("Q_sc", "Q_sc_C"), ("I_sc", "I_sc_A"),
                        ("C_T", "C_T_F"), ("V_read", "V_read_V")]:
        np.testing.assert_array_equal(rows[key], np.asarray(result.waveforms[column]), key)


@settings(max_examples=25, deadline=None)
@given(size=st.integers(min_value=1, max_value=7000))
def test_the_chunks_are_the_whole_record(result, size):
    """Any chunk size: the chunks cover the rows once, in order, with the whole record's
    values (every quantity is pointwise in time)."""
    source = Source.of_scene(result.scene, result.curves, result.dynamics)
    whole = source.rows()
    parts = list(source.chunks(size))
    assert parts[0][0] == 0 and parts[-1][1] == source.samples
    assert all(a[1] == b[0] for a, b in zip(parts, parts[1:]))
    for key in QUANTITIES:
        np.testing.assert_array_equal(np.concatenate([p[2][key] for p in parts]), whole[key])


def test_the_voltages_are_the_charge_over_the_capacitance(result):
    rows = Source.of_scene(result.scene, result.curves, result.dynamics).rows()
    c_p = result.scene.circuit.parallel_capacitance
    assert c_p == pytest.approx(50e-12)
    np.testing.assert_allclose(rows["V_oc"], rows["Q_sc"] / rows["C_T"], rtol=1e-13)
    np.testing.assert_allclose(rows["V_read"], rows["Q_sc"] / (rows["C_T"] + c_p), rtol=1e-13)
    assert np.ptp(rows["Q_sc"]) > 0.0


def test_the_current_is_the_rate_of_the_charge(result):
    """I_SC = dQ_SC/dt: the trapezoidal integral of I_SC over a step equals the step in
    Q_SC wherever no impact lies inside it (to the step's O(h^3) rule)."""
    source = Source.of_scene(result.scene, result.curves, result.dynamics)
    t = source.elapsed()
    rows = source.rows()
    impacts = electrical.impact_elapsed(result.dynamics, t[0], t[-1])
    step = np.searchsorted(impacts, t[:-1], side="right") == \
        np.searchsorted(impacts, t[1:], side="left")        # no impact in [t_i, t_i+1]
    dq = np.diff(rows["Q_sc"])[step]
    integral = (0.5 * (rows["I_sc"][1:] + rows["I_sc"][:-1]) * np.diff(t))[step]
    scale = np.max(np.abs(rows["Q_sc"]))
    assert step.sum() > 0.9 * step.size
    assert np.max(np.abs(dq - integral)) < 1e-3 * scale


@pytest.mark.parametrize("cells", [1, 3, 16])
def test_cells_in_parallel_are_that_many_times_one(result, cells):
    one = Source(result.curves, result.dynamics).rows()
    many = Source(result.curves, result.dynamics, cells=cells).rows()
    for key in ("Q_sc", "I_sc", "C_T", "dC_T_dt"):
        np.testing.assert_allclose(many[key], cells * one[key], rtol=1e-14, atol=0.0)
    np.testing.assert_allclose(many["V_oc"], one["V_oc"], rtol=1e-13)


def test_the_state_is_the_rows_charge_and_capacitance(result):
    source = Source.of_scene(result.scene, result.curves, result.dynamics)
    rows = source.rows()
    q, c = source.state(source.elapsed(), rows["gap"])
    np.testing.assert_allclose(q, rows["Q_sc"], rtol=1e-12, atol=1e-12 * np.ptp(q))
    np.testing.assert_allclose(c, rows["C_T"], rtol=1e-12)


def test_nothing_charged(result):
    source = Source(None, result.dynamics, cells=4)
    assert not source.charged and not source.radial and not source.contact
    rows = source.rows(0, 10)
    assert np.all(rows["Q_sc"] == 0.0) and np.all(rows["I_sc"] == 0.0)
    assert np.all(np.isnan(rows["C_T"]))
    q, c = source.state(source.elapsed(0, 10), rows["gap"])
    assert np.all(q == 0.0) and np.all(np.isnan(c))
    assert source.ball_charge([0.0, 0.1]) is None


def test_a_contact_charged_source_follows_its_history(cache):
    """``[charge] model = "contact"``: the source's ball charge is the history's, and its
    rows are the run's columns (the charge column too)."""
    scene = fx.scene_with(run=RUN, charge={"model": "contact", "equilibrium_uC_per_m2": -20.0,
                                             "efficiency": 0.3, "initial_uC_per_m2": -2.0,
                                             "discharge": "none"})
    out = tf.run(scene, cache_dir=cache, solve=fx.plate_model_solve)
    source = Source.of_scene(out.scene, out.curves, out.dynamics)
    assert source.contact
    t = source.elapsed()
    q = source.ball_charge(t)
    assert np.ptp(q) > 0.0                       # the contacts charge it
    np.testing.assert_array_equal(q, out.curves.terminal.ball_charge(t))
    np.testing.assert_array_equal(source.rows()["Q_sc"], np.asarray(out.waveforms["Q_sc_C"]))


def test_each_cell_is_the_terminal_of_one_cell_per_column(result):
    """An [array]'s cells with their own motion: the compiled splines over every column
    give one cell's Q_SC, C_T, I_SC as :meth:`Source.terminal` does, column by column."""
    source = Source(result.curves, result.dynamics)
    rows = source.rows()
    t = source.elapsed()
    shift = np.roll(np.arange(t.size), 137)            # a second cell, another phase
    gap = np.column_stack([rows["gap"], rows["gap"][shift]])
    rate = np.column_stack([rows["gap_velocity"], rows["gap_velocity"][shift]])
    q, c, i = source.each_cell(t, gap, rate)
    assert q.shape == c.shape == i.shape == gap.shape
    for j in range(2):
        one = source.terminal(t, gap[:, j], rate[:, j])
        scale = np.max(np.abs(one["Q_sc"]))
        np.testing.assert_allclose(q[:, j], one["Q_sc"], rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(c[:, j], one["C_T"], rtol=1e-12)
        np.testing.assert_allclose(i[:, j], one["I_sc"], rtol=0,
                                   atol=1e-12 * np.max(np.abs(one["I_sc"])))
