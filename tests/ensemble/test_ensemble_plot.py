"""ensemble.png: the running mean and interval of each output, the regime fractions."""
import math

import numpy as np
import pytest

from tengfield.ensemble import ensemble_block


def _rows(values):
    return [{"realisation": k, "seed": k, "regime": "chaos" if k % 2 else "bounce",
             "V_oc_pp_V": v, "Q_sc_pp_C": 1e-10, "I_sc_pp_A": 1e-8, "mean_power_W": None,
             "power_density_W_per_m3": None, "average_harvested_power_W": None,
             "final_stored_energy_J": None, "array_value": None}
            for k, v in enumerate(values)]


def test_running_mean_leaves_missing_values_out():
    """A realisation without a value (NaN) was drawn as 0: it pulled the running mean and
    widened the interval. The running statistics are those of the values so far."""
    from tengfield.plotting.ensemble import _running_interval
    n, mean, half = _running_interval(np.array([1.0, math.nan, 3.0, 5.0]))
    assert list(n) == [1, 2, 3, 4]
    assert mean[-1] == pytest.approx(3.0) and mean[2] == pytest.approx(2.0)
    # the last interval is the Student interval of [1, 3, 5]: t(0.975, 2) 2 / sqrt(3)
    assert half[-1] == pytest.approx(4.302652729911275 * 2.0 / math.sqrt(3.0))


def test_the_figure_is_drawn_with_a_missing_value_and_two_regimes(tmp_path):
    from tengfield.plotting.ensemble import plot_ensemble
    rows = _rows([1.0, math.nan, 3.0, 5.0])
    path = plot_ensemble(rows, ensemble_block(rows), tmp_path / "ensemble.png")
    assert path.stat().st_size > 10_000


@pytest.mark.slow
def test_the_block_plots_itself_and_stays_the_summary_dict(tmp_path):
    """#29: ``ensemble_block(rows).plot()`` (``RunResult.ensemble.plot()``) is the figure
    plot_ensemble saves; the block is still the plain summary.json dict (pickled too, as
    mpirun ranks send it)."""
    import json
    import pickle

    from matplotlib.figure import Figure

    from tengfield.plotting.ensemble import plot_ensemble
    from tengfield.quantities import axis_label

    rows = _rows([1.0, 2.0, 4.0])
    block = ensemble_block(rows)
    fig = block.plot()
    assert isinstance(fig, Figure)
    assert fig.axes[0].get_ylabel() == axis_label("V_oc_V", statistic="peak_to_peak")
    assert list(fig.axes[0].get_lines()[0].get_ydata()) == [1.0, 2.0, 4.0]
    plot_ensemble(rows, block, tmp_path / "cli.png")
    fig.savefig(tmp_path / "notebook.png", dpi=110)
    assert (tmp_path / "cli.png").read_bytes() == (tmp_path / "notebook.png").read_bytes()
    assert json.loads(json.dumps(block)) == json.loads(json.dumps(dict(block)))
    again = pickle.loads(pickle.dumps(block))
    assert again == block and again.rows == rows
