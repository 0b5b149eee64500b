"""The default cold surrogate against the table computed before the issue-9 speed work
(tests/data/surrogate_before_issue9.json, every position's own field error estimate):
faster, and no less accurate. Speed itself is measured in benchmarks/pipeline_speed.py."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

BASELINE = json.loads((Path(__file__).resolve().parents[1] / "data" / "surrogate_before_issue9.json")
                      .read_text())


@pytest.fixture(scope="module")
def table():
    import pyvista  # noqa: F401 - before dolfinx

    from tengfield import surrogate
    from tengfield.scene import default_scene

    return surrogate.precompute(default_scene())


pytestmark = [pytest.mark.field, pytest.mark.slow]


def test_same_positions_and_values_within_the_error_estimates(table):
    """C and q at every position agree with the earlier table within the two field error
    estimates (the meshes differ, the physics does not); the earlier table's charges [C]
    were at the default scene's ball charge, today's are per unit charge."""
    from tengfield.scene import default_scene

    np.testing.assert_array_equal(table.positions, BASELINE["positions_m"])
    before_C = np.asarray(BASELINE["capacitance_F"])
    before_q = np.asarray(BASELINE["induced_charge_C"])
    q = table.induced_charges(default_scene().device.ball_charge)
    allowed = np.asarray(BASELINE["field_error"]) + np.asarray(table.field_error)
    for i in range(len(table.positions)):
        dC = np.max(np.abs(table.capacitance[i] - before_C[i])) / np.max(np.abs(before_C[i]))
        dq = np.max(np.abs(q[i] - before_q[i])) / np.max(np.abs(before_q[i]))
        assert max(dC, dq) <= allowed[i], (table.positions[i], dC, dq, allowed[i])


def _measured(table) -> np.ndarray:
    """Indices of the positions whose own field error the default surrogate measures (and
    their mirror images)."""
    from tengfield import surrogate

    sampled = surrogate.error_sample_positions(table.stroke, True)
    mirrored = np.concatenate([sampled, table.stroke - sampled])
    return np.flatnonzero(np.min(np.abs(table.positions[:, None] - mirrored[None, :]),
                                 axis=1) < 1e-12 * table.stroke)


def test_field_error_where_measured_is_no_larger_than_before(table):
    """Where the default (sampled) surrogate measures the field error, its estimate is at
    most the earlier one at the same position; everywhere else the value carried over
    covers the earlier estimate there."""
    before = np.asarray(BASELINE["field_error"])
    measured = _measured(table)
    assert 3 <= measured.size < before.size
    for i in measured:
        assert table.field_error[i] <= before[i], (table.positions[i], table.field_error[i],
                                                   before[i])
    others = np.setdiff1d(np.arange(before.size), measured)
    assert np.all(table.field_error[others] >= before[others])


def test_total_error_bar_is_no_larger_than_before(table):
    """The largest measured field error plus the interpolation error (the error bar of the
    surrogate's values) is no larger than before; the interpolation error alone stays far
    inside the tolerance (it mostly measures the remeshing noise between positions)."""
    field_now = float(np.max(table.field_error[_measured(table)]))
    before = max(BASELINE["field_error"]) + BASELINE["interpolation_error"]
    assert field_now + table.interpolation_error <= before
    assert table.interpolation_error <= 0.1 * table.tolerance
