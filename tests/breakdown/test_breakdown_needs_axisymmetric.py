"""The breakdown lines come only from the axisymmetric solver: a scene or command that
needs them with ``[field] method = "3d"`` is refused at once, naming the keys, before
any field solve; and a run never goes on at the stand-in sigma of ``"breakdown"``."""
from __future__ import annotations

import numpy as np
import pytest

from tengfield import air_breakdown
from tengfield.errors import TengfieldError
from tengfield.scene import SceneError, check_field
from tengfield.scene import parse_scene as load_scene_text

THREE_D_BREAKDOWN = """
[device]
surface_charge_uC_per_m2 = "breakdown"
[field]
method = "3d"
"""


def test_scene_names_the_keys():
    scene = load_scene_text(THREE_D_BREAKDOWN)        # a dynamics-only run needs no field
    with pytest.raises(SceneError, match=r'surface_charge_uC_per_m2 = "breakdown".*'
                                         r"method = '3d'"):
        check_field(scene)
    # the axisymmetric solver (the default) has the lines: accepted
    check_field(load_scene_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'))


def test_breakdown_table_of_a_3d_scene_is_refused_before_solving(tmp_path):
    scene = load_scene_text("[field]\nmethod = \"3d\"\n")

    def solve_must_not_run(*args, **kwargs):
        raise AssertionError("a field solve ran")
    with pytest.raises(TengfieldError, match="axisymmetric"):
        air_breakdown.obtain_breakdown_table(scene, cache_dir=tmp_path)
    assert not any(tmp_path.iterdir())


def test_a_run_never_uses_the_stand_in_sigma(tmp_path):
    """A surrogate without lines (custom solve) and sigma = "breakdown": an error, not a
    run at -1 uC/m^2."""
    scene = load_scene_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n')

    class NoLines:
        line_potential = None
    with pytest.raises(TengfieldError, match="no breakdown lines"):
        air_breakdown.resolve_for_run(scene, NoLines())
    # with a numeric sigma the run goes on without a breakdown block
    numeric = load_scene_text("[device]\nsurface_charge_uC_per_m2 = -8.0\n")
    out_scene, table, result = air_breakdown.resolve_for_run(numeric, NoLines())
    assert result is None and out_scene is numeric
    assert np.isclose(out_scene.device.surface_charge, -8e-6)


def test_cli_refuses_at_once(tmp_path, run_cli):
    (tmp_path / "s.toml").write_text(THREE_D_BREAKDOWN)
    for args in (("run", "s.toml", "-o", "out", "--no-plots"), ("scene", "s.toml"),
                 ("breakdown", "s.toml", "-o", "bd")):
        proc = run_cli(*args, cwd=tmp_path, timeout=120)
        assert proc.returncode != 0 and "Traceback" not in proc.stderr, proc.stderr
        assert proc.stderr.startswith("tengfield: error:") and "axisymmetric" in proc.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "bd").exists()


def test_an_off_axis_ball_is_refused_too():
    scene = load_scene_text('[device]\nsurface_charge_uC_per_m2 = "breakdown"\n'
                            '[field]\nmethod = "auto"\nball_offset_mm = 0.5\n')
    with pytest.raises(SceneError, match=r"ball_offset_mm = 0\.5"):
        check_field(scene)
