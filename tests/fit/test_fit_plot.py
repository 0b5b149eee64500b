"""#29 notebook use: ``FitResult.plot()`` returns the matplotlib Figure that
``tengfield fit`` saves as fit.png (measured against fitted, with the residuals)."""
from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from tengfield.fit import fit_trace, parse_fit_section

from fit_synthetic import synthetic


@pytest.mark.slow
def test_fit_result_plot_is_the_fit_figure(plate_scene, plate_surrogate, tmp_path):
    trace, _ = synthetic(plate_scene, plate_surrogate, 0)
    spec = parse_fit_section(plate_scene.with_values(fit={"parameters": {
        "surface_charge_uC_per_m2": {"start": -10.0}, "time_shift_s": {}}}))
    result = fit_trace(plate_scene, plate_surrogate[0], plate_surrogate[1], trace, spec)
    fig = result.plot()
    assert isinstance(fig, Figure)
    assert [ax.get_ylabel() for ax in fig.axes] == ["V_read [V]", "residual [V]", "Q_SC [nC]",
                                                  "residual [nC]"]  # the quantity table's labels
    assert fig.axes[-1].get_xlabel() == "measured time [s]"
    assert "σ = " in fig.axes[0].get_title()          # the symbol, not the scene key
    measured = fig.axes[0].get_lines()[0].get_ydata()
    assert np.array_equal(measured, np.asarray(result.measured["V"]))
    from tengfield.plotting.fit import plot_fit
    plot_fit(result, tmp_path / "cli.png")
    from tengfield.plotting.fit import FIT_DPI
    fig.savefig(tmp_path / "notebook.png", dpi=FIT_DPI)
    assert (tmp_path / "cli.png").read_bytes() == (tmp_path / "notebook.png").read_bytes()
