"""#29 notebook use: ``BreakdownResult.plot()`` returns the matplotlib Figure that
``tengfield breakdown`` saves as breakdown.png (coarse field solves)."""
import pytest
from matplotlib.figure import Figure

from tengfield import air_breakdown
from tengfield.scene import default_scene


@pytest.mark.slow
@pytest.mark.field
def test_breakdown_result_plot_is_the_breakdown_figure(tmp_path):
    scene = default_scene().with_values(field={"degree": 1, "mesh_size_mm": 1.0,     # coarse:
                                               "tolerance": 0.1})   # its estimate is ~0.08
    table, _ = air_breakdown.obtain_breakdown_table(scene, cache_dir=tmp_path / "cache")
    result = air_breakdown.scene_breakdown(scene, table)
    fig = result.plot(scene.device.surface_charge)
    assert isinstance(fig, Figure)
    left, right = fig.axes
    assert left.get_xlabel() == "gap length along the line [mm]"
    assert right.get_ylabel() == "|V_gap| / V_b (worst line)"
    assert f"σ_max = {result.sigma_max * 1e6:.3g} µC/m²" in fig._suptitle.get_text()
    assert "−" + f"{result.sigma_max * 1e6:.3g}" in result.plot()._suptitle.get_text()
    air_breakdown.write_outputs(result, scene, tmp_path / "cli", plots=True)
    fig.savefig(tmp_path / "notebook.png", dpi=120)     # breakdown.png's dpi
    assert (tmp_path / "notebook.png").read_bytes() == \
        (tmp_path / "cli" / "breakdown.png").read_bytes()
