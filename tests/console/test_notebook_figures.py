"""#29 notebook use: the results' ``plot()`` return a matplotlib Figure (the one the CLI
saves), and ``RunResult.to_dataframe()`` gives the waveforms as a pandas DataFrame when
pandas is installed (a clear ImportError otherwise; pandas is not a dependency)."""
from __future__ import annotations

import sys

import numpy as np
import pytest
from matplotlib.figure import Figure

import plate_model as fx
from tengfield import pipeline

SHORT = {"run": {"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000.0}}


def _labels(fig) -> list[str]:
    return [ax.get_ylabel() for ax in fig.axes]


@pytest.fixture(scope="module")
def run_result(tmp_path_factory):
    """A real run of the default device (impact map), the analytic plate-model field."""
    scene = fx.scene_with(**SHORT)
    return pipeline.run(scene, cache_dir=tmp_path_factory.mktemp("cache"),
                        solve=fx.plate_model_solve)


@pytest.mark.slow
def test_run_result_plot_is_the_waveforms_figure(run_result, tmp_path):
    fig = run_result.plot()
    assert isinstance(fig, Figure)
    labels = _labels(fig)
    assert labels[:3] == ["V_OC [V]", "Q_SC [nC]", "I_SC [nA]"]
    assert labels[3:] == ["gap z [mm]"]                      # the gap's own panel
    assert fig.axes[3].get_xlabel() == "time [ms]"
    # the last 5 periods, as waveforms.png; the plotted V_OC is the run's
    t_ms, v = fig.axes[0].get_lines()[0].get_data()
    period_ms = 1e3 * run_result.scene.excitation.period
    assert t_ms[-1] - t_ms[0] == pytest.approx(5 * period_ms, abs=0.5)
    assert np.array_equal(v, run_result.V_oc[-v.size:])
    whole = run_result.plot(last_periods=None)
    assert whole.axes[0].get_lines()[0].get_data()[1].size == run_result.t.size
    # the CLI's PNG is this figure: the same pixels
    from tengfield.io import write_run_outputs
    write_run_outputs(run_result, tmp_path / "cli", plots=True)
    fig.savefig(tmp_path / "notebook.png", dpi=120)
    assert (tmp_path / "notebook.png").read_bytes() == \
        (tmp_path / "cli" / "waveforms.png").read_bytes()


@pytest.mark.slow
def test_run_result_to_dataframe(run_result, monkeypatch):
    pandas = pytest.importorskip("pandas")
    df = run_result.to_dataframe()
    assert isinstance(df, pandas.DataFrame)
    assert list(df.columns[:4]) == ["time_s", "gap_m", "V_oc_V", "Q_sc_C"] or \
        list(df.columns[:1]) == ["time_s"]
    assert len(df) == run_result.t.size
    assert np.array_equal(df["V_oc_V"].to_numpy(), run_result.V_oc)
    monkeypatch.setitem(sys.modules, "pandas", None)      # pandas not installed
    with pytest.raises(ImportError, match="needs pandas.*pip install pandas"):
        run_result.to_dataframe()


@pytest.mark.slow
def test_dynamics_and_map_plots_are_figures():
    from tengfield.dynamics import regime_map, simulate

    scene = fx.scene_with(**SHORT)
    dyn = simulate(scene)
    fig = dyn.plot()
    assert isinstance(fig, Figure)
    assert _labels(fig) == ["position [mm]", "gap $z$ [mm]"]
    gap_line = fig.axes[1].get_lines()[0]
    assert np.max(gap_line.get_ydata()) <= scene.device.stroke * 1e3 * (1 + 1e-9)
    rmap = regime_map(scene, [15.0, 25.0], [1e-3, 2e-3], jobs=1, progress=False, periods=20)
    fig = rmap.plot(title="a map")
    assert isinstance(fig, Figure)
    assert fig.axes[0].get_xlabel() == "frequency [Hz]"
    assert fig.axes[0].get_title() == "a map"


@pytest.mark.slow
def test_sweep_rows_plot(tmp_path):
    from tengfield import surrogate
    from tengfield.sweeps import sweep

    scene = fx.scene_with(**SHORT)
    table, _ = surrogate.obtain_table(scene, cache_dir=tmp_path, solve=fx.plate_model_solve)
    rows = sweep(scene, table, [20.0, 25.0], [1.5e-3], jobs=1)
    assert len(rows) == 2 and isinstance(rows, list)
    fig = rows.plot()
    assert isinstance(fig, Figure)
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "V_OC peak-to-peak [V]", "Q_SC peak-to-peak [nC]", "I_SC peak-to-peak [nA]"]
    freqs, volts = fig.axes[0].get_lines()[0].get_data()
    assert list(freqs) == [20.0, 25.0]
    assert list(volts) == [r["V_oc_pp_V"] for r in rows]
