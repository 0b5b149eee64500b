"""The surrogate per unit ball charge (issue #51): a table holds the capacitance matrix and
the induced fractions q_k / q_ball (no ball charge, no σ in its file or its cache key); the
ball's charge enters where the curves are built, ``TerminalCurves(table, reference,
ball_charge)``. Files of the old layout (charges in C at the ball charge solved with) are
read and converted; one written at a zero ball charge is refused in one line."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tengfield import surrogate, terminals
from tengfield.surrogate import SurrogateError, TerminalCurves

import plate_model as fx
from zr_model import zr_model

h5py = surrogate._import_h5py()

DATA = Path(__file__).resolve().parents[1] / "data"
#: written by tests/data/make_format3_surrogates.py with the code before the per-unit table
OLD_1D = DATA / "surrogate_format3_plate.h5"
OLD_1D_UNCHARGED = DATA / "surrogate_format3_plate_uncharged.h5"
OLD_ZR = DATA / "surrogate_zr_format1_plate.h5"
SOLVE_COMM = object()   # the analytic model needs no communicator


def _sigma(scene, uc):
    return scene.with_values(device={"surface_charge_uC_per_m2": uc})


SCENE = _sigma(fx.scene_with(), -8.0)       # the scene the old files were written for


def _table(scene=SCENE):
    return surrogate.precompute(scene, solve=fx.plate_model_solve, solve_comm=SOLVE_COMM)


def _old_file(path):
    """The raw datasets and attributes of an old-layout file (no tengfield reader)."""
    with h5py.File(path, "r") as f:
        return {k: f[k][()] for k in f}, dict(f.attrs)


# ---------------------------------------------------------------------------
# (a) per unit charge x q = the induced charges at q
def test_the_table_holds_fractions_and_no_ball_charge():
    table = _table()
    assert not hasattr(table, "ball_charge") and not hasattr(table, "induced_charge_C")
    assert "ball_charge_C" not in table.summary and "induced_charge_C" not in table.summary
    np.testing.assert_array_equal(np.asarray(table.summary["induced_fraction"]),
                                  table.induced_fraction)
    # the plate model's Shockley-Ramo shares, per unit charge: q_k / q_ball = -share
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(SCENE, table.positions)
    q = SCENE.device.ball_charge
    np.testing.assert_allclose(table.induced_fraction, np.column_stack([q_l, q_u]) / q,
                               rtol=1e-12, atol=0)
    assert np.all((table.induced_fraction < 0) & (table.induced_fraction > -1))


@pytest.mark.parametrize("uc", [-8.0, -20.0, 3.0])
def test_fractions_times_the_charge_are_the_induced_charges_at_that_charge(uc):
    """The field is linear in the ball's charge: the table of one σ, times any q, gives
    the charges a solve at that q gives, and the curves the terminal quantities of
    tengfield.terminals at q."""
    table = _table()                         # solved at -8 µC/m²
    at = _sigma(fx.scene_with(), uc)
    q = at.device.ball_charge
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(at, table.positions)   # solved at q
    np.testing.assert_allclose(table.induced_charges(q), np.column_stack([q_l, q_u]),
                               rtol=1e-12, atol=0)
    for reference in terminals.REFERENCES:
        curves = TerminalCurves(table, reference, q)
        q0 = terminals.upper_short_circuit_charge(*fx.plate_model(at, 0.0), q, reference)
        q_sc = terminals.upper_short_circuit_charge(c_ll, c_lu, c_uu, q_l, q_u, q,
                                                    reference) - q0
        np.testing.assert_allclose(curves.charge_samples, q_sc, rtol=1e-12,
                                   atol=1e-12 * np.max(np.abs(q_sc)))
        assert curves.ball_charge == q


def test_the_old_files_charges_are_the_new_tables_fractions_times_its_charge():
    """The induced charges the old code wrote (format 3, at its ball charge) are today's
    fractions (solved afresh) times that charge."""
    arrays, attrs = _old_file(OLD_1D)
    table = _table()
    np.testing.assert_array_equal(arrays["positions_m"], table.positions)
    np.testing.assert_allclose(table.induced_charges(attrs["ball_charge_C"]),
                               arrays["induced_charge_C"], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(arrays["capacitance_F"], table.capacitance)


# ---------------------------------------------------------------------------
# (b) σ is in neither the key nor the table: one cache entry, outputs scale exactly
def test_two_sigmas_share_one_cache_entry_and_scale_exactly(tmp_path):
    """Scenes differing only in σ: the second is a cache hit with no solve, its table is
    the first's, and Q_SC, V_OC, I_SC scale by the σ ratio (sign included) with C_T and
    dC_T/dt unchanged, along a trajectory."""
    solver = fx.CountingSolver()
    first, outcome = surrogate.obtain_table(SCENE, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "computed" and solver.calls > 0
    calls = solver.calls
    t = np.linspace(0.0, 0.2, 401)
    stroke = SCENE.device.stroke
    z = 0.5 * stroke * (1.0 - np.cos(2 * np.pi * 15.0 * t))
    z_rate = 0.5 * stroke * 2 * np.pi * 15.0 * np.sin(2 * np.pi * 15.0 * t)
    ref = TerminalCurves(first, "floating", SCENE.device.ball_charge)
    q_ref, i_ref, c_ref, dc_ref = ref.evaluate_many(z, z_rate, cells=3)
    v_ref = ref.voltage(z)
    assert np.ptp(q_ref) > 0 and np.ptp(i_ref) > 0
    for uc in (-20.0, 8.0, -8.0):
        scene = _sigma(SCENE, uc)
        assert scene.field_hash() == SCENE.field_hash()
        table, outcome = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=solver)
        assert outcome.status == "cached" and solver.calls == calls, uc
        assert table.scene is scene
        np.testing.assert_array_equal(table.induced_fraction, first.induced_fraction)
        np.testing.assert_array_equal(table.capacitance, first.capacitance)
        ratio = uc / -8.0
        curves = TerminalCurves(table, "floating", scene.device.ball_charge)
        q_sc, i_sc, c_t, dc_dt = curves.evaluate_many(z, z_rate, cells=3)
        for ours, theirs in ((q_sc, q_ref), (i_sc, i_ref), (curves.voltage(z), v_ref)):
            np.testing.assert_allclose(ours, ratio * theirs, rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(theirs)))
        np.testing.assert_array_equal(c_t, c_ref)
        np.testing.assert_array_equal(dc_dt, dc_ref)
    assert len(list(tmp_path.glob("surrogate-*.h5"))) == 1


def test_the_cache_file_holds_no_charge(tmp_path):
    """surrogate.h5 states its units: the fractions (dimensionless), no ball charge, no
    dataset or scalar in coulombs."""
    surrogate.obtain_table(SCENE, cache_dir=tmp_path, solve=fx.plate_model_solve)
    with h5py.File(surrogate.cache_path(SCENE, tmp_path), "r") as f:
        assert int(f.attrs["format_version"]) == surrogate.FORMAT_VERSION
        assert "induced_fraction" in f
        assert not [k for k in (*f, *f.attrs) if k.endswith("_C")]


# ---------------------------------------------------------------------------
# (c) files of the old layout: read, converted
def test_an_old_layout_file_is_read_per_unit_charge():
    """The format-3 file the old code wrote: its fractions are the plate model's own
    shares, and its curves at any charge are those of a table solved today."""
    old = surrogate.read_table(OLD_1D)
    _, attrs = _old_file(OLD_1D)
    assert int(attrs["format_version"]) == 3
    c_ll, c_lu, c_uu, q_l, q_u = fx.plate_model(SCENE, old.positions)
    np.testing.assert_allclose(old.induced_fraction,
                               np.column_stack([q_l, q_u]) / SCENE.device.ball_charge,
                               rtol=1e-12, atol=0)
    assert old.provenance["converted_from"] == {"format": 3,
                                                "ball_charge_C": attrs["ball_charge_C"]}
    new = _table()
    z = np.linspace(0.0, SCENE.device.stroke, 97)
    for uc in (-8.0, 12.0):
        q = _sigma(SCENE, uc).device.ball_charge
        for reference in terminals.REFERENCES:
            a, b = TerminalCurves(old, reference, q), TerminalCurves(new, reference, q)
            np.testing.assert_allclose(a.charge(z), b.charge(z), rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(b.charge(z))))
            np.testing.assert_array_equal(a.capacitance(z), b.capacitance(z))


def test_an_old_layout_zr_file_is_read_per_unit_charge():
    """The (z, r) format-1 file: its fractions are the (z, r) model's shares."""
    old = surrogate.read_radial_table(OLD_ZR)
    _, attrs = _old_file(OLD_ZR)
    assert int(attrs["format_version"]) == 1 and str(attrs["kind"]) == "zr"
    zz, rr = np.meshgrid(old.positions, old.offsets, indexing="ij")
    c_ll, c_lu, c_uu, q_l, q_u = zr_model(SCENE, zz, rr)
    np.testing.assert_allclose(old.induced_fraction,
                               np.stack([q_l, q_u], -1) / SCENE.device.ball_charge,
                               rtol=1e-12, atol=0)
    assert old.provenance["converted_from"]["format"] == 1
    q = SCENE.device.ball_charge
    curves = old.curves("floating", q)
    q_grid, _ = surrogate.terminal_grid(old, "floating", q)
    np.testing.assert_allclose(curves.charge(zz, rr), q_grid, rtol=1e-9,
                               atol=1e-12 * np.max(np.abs(q_grid)))


def _write_old_layout(path, table, ball_charge):
    """``table`` as the old code wrote it (format 3: ``induced_charge_C`` [C] at
    ``ball_charge`` and the scalar ``ball_charge_C`` in the scalars' checksum), with the
    dataset and attribute names spelled out here, not taken from tengfield's layout."""
    from tengfield.files.hdf5 import write_checked_file

    arrays = {"positions_m": table.positions, "capacitance_F": table.capacitance,
              "induced_charge_C": table.induced_fraction * ball_charge,
              "dofs": table.dofs, "cells": table.cells, "wall_time_s": table.wall_time,
              "solve_time_s": table.solve_time,
              "field_relative_error_estimate": table.field_error,
              "error_history": np.asarray(table.error_history, dtype=float).reshape(-1, 2)}
    scalars = {"ball_charge": float(ball_charge), "stroke": float(table.stroke),
               "interpolation_error": float(table.interpolation_error),
               "tolerance": float(table.tolerance), "converged": bool(table.converged),
               "field_hash": str(table.field_hash), "method": str(table.method),
               "degree": int(table.degree)}
    names = {"ball_charge": "ball_charge_C", "stroke": "stroke_m",
             "interpolation_error": "interpolation_error_estimate", "tolerance": "tolerance",
             "converged": "converged", "field_hash": "field_hash", "method": "method",
             "degree": "degree"}
    return write_checked_file(path, {k: np.asarray(v) for k, v in arrays.items()}, scalars,
                              names, {"format_version": 3,
                                      "provenance": json.dumps(table.provenance, default=str)},
                              error=SurrogateError)


def test_the_old_layout_writer_here_is_the_old_codes(tmp_path):
    """What :func:`_write_old_layout` writes reads back as the file the old code wrote."""
    old = surrogate.read_table(OLD_1D)
    _, attrs = _old_file(OLD_1D)
    again = surrogate.read_table(_write_old_layout(tmp_path / "again.h5", old,
                                                   attrs["ball_charge_C"]))
    np.testing.assert_allclose(again.induced_fraction, old.induced_fraction, rtol=1e-15)
    np.testing.assert_array_equal(again.capacitance, old.capacitance)


def test_an_old_layout_cache_file_is_a_hit_with_no_solve(tmp_path):
    """A cache entry the old code wrote (at -8 µC/m²) serves a scene at -20 µC/m²: no
    solve, and its curves are the fresh table's at -20."""
    table = _table()
    _write_old_layout(surrogate.cache_path(SCENE, tmp_path), table, SCENE.device.ball_charge)
    solver = fx.CountingSolver()
    at = _sigma(SCENE, -20.0)
    got, outcome = surrogate.obtain_table(at, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "cached" and solver.calls == 0
    q = at.device.ball_charge
    np.testing.assert_allclose(TerminalCurves(got, "floating", q).charge_samples,
                               TerminalCurves(table, "floating", q).charge_samples,
                               rtol=1e-12, atol=1e-24)


# ---------------------------------------------------------------------------
# (d) an old file at a zero ball charge: refused in one line
def test_an_old_file_at_zero_ball_charge_is_refused_in_one_line():
    _, attrs = _old_file(OLD_1D_UNCHARGED)
    assert attrs["ball_charge_C"] == 0.0 and int(attrs["format_version"]) == 3
    with pytest.raises(SurrogateError) as caught:
        surrogate.read_table(OLD_1D_UNCHARGED)
    message = str(caught.value)
    assert "\n" not in message
    assert str(OLD_1D_UNCHARGED) in message
    assert "ball charge of 0.0 C" in message and "no charge per unit ball charge" in message
    assert "solve it again" in message


def test_an_old_cache_file_at_zero_ball_charge_is_recomputed_with_a_warning(tmp_path):
    table = _table()
    path = _write_old_layout(surrogate.cache_path(SCENE, tmp_path), table, 0.0)
    solver = fx.CountingSolver()
    with pytest.warns(RuntimeWarning, match=r"not trusted \(was written by an older tengfield "
                                            r"\(format 3.*ball charge of 0\.0 C"):
        got, outcome = surrogate.obtain_table(SCENE, cache_dir=tmp_path, solve=solver)
    assert outcome.status == "recomputed" and solver.calls > 0
    np.testing.assert_allclose(got.induced_fraction, table.induced_fraction, rtol=1e-15)
    assert int(h5py.File(path, "r").attrs["format_version"]) == surrogate.FORMAT_VERSION


def test_curves_refuse_mixed_ball_charges():
    """The anchored (z, r) curves take one ball charge: an axis and a (z, r) part at two
    charges are refused, not added."""
    from zr_model import zr_model_solve

    table = _table()
    zr = surrogate.precompute_radial(SCENE, solve=zr_model_solve, solve_comm=SOLVE_COMM,
                                     tolerance=1e-2, max_positions=17, max_offsets=9)
    q = SCENE.device.ball_charge
    surrogate.AnchoredTerminalCurves(zr.curves("floating", q), table.curves("floating", q))
    with pytest.raises(ValueError, match="ball charges differ"):
        surrogate.AnchoredTerminalCurves(zr.curves("floating", q),
                                         table.curves("floating", 2 * q))


def test_a_mirror_image_swaps_the_fractions_with_the_charges():
    """The table reads the fractions of every solve, the mirrored ones included: the image
    of a solve at z is the solve at Δh − z (the plate model is mirror-symmetric)."""
    stroke = SCENE.device.stroke
    for z in (0.0, 0.3e-3, 0.37 * stroke):
        image = surrogate.mirrored(fx.plate_model_solve(SCENE, z), stroke)
        direct = fx.plate_model_solve(SCENE, stroke - z)
        np.testing.assert_allclose(image.induced_fraction, direct.induced_fraction, rtol=1e-12)
        np.testing.assert_allclose(image.induced_charge, direct.induced_charge, rtol=1e-12)
        assert image.induced_fraction[0] != image.induced_fraction[1]
