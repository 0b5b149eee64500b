"""fit.json, fit.png and fitted.toml (the scene with the fitted values, ready for ``tengfield run``)."""
from __future__ import annotations

from pathlib import Path

from ..files import one_line, scene_dir, scene_toml, write_json, write_text
from ..files import figure_file
from ..scene.schema import SURFACE_CHARGE_KEY

#: where each fitted parameter goes in the scene file (time_shift_s has no scene key)
SCENE_KEYS = {
    SURFACE_CHARGE_KEY: ("device", SURFACE_CHARGE_KEY),
    # the instrument's C_p (issue #39: [circuit] parallel_capacitance_pF is its old name)
    "parallel_capacitance_pF": ("instrument", "capacitance_pF"),
    "restitution": ("contact", "restitution"),
    "load_ohm": ("circuit", "load_ohm"),
}


def fitted_scene_dict(scene, result) -> dict:
    """``scene.raw`` with the fitted values, every section whole ([fit], [design.vary],
    [uncertainty.vary] ... kept: issue #43.1; :func:`tengfield.files.scene_toml` writes
    the sub-tables)."""
    import copy

    data = copy.deepcopy(dict(scene.raw))
    for name, value in result.values.items():
        if name in SCENE_KEYS:
            sec, key = SCENE_KEYS[name]
            data.setdefault(sec, {})[key] = float(f"{value:.6g}")
            if name == "parallel_capacitance_pF":        # one name of C_p, the new one
                data.get("circuit", {}).pop("parallel_capacitance_pF", None)
        elif name == "amplitude_scale":
            data.setdefault("excitation", {})["amplitude_mm"] = float(
                f"{scene.excitation.amplitude * 1e3 * value:.6g}")
    return data


def write_fit_outputs(scene, result, out_dir, *, plots: bool = True) -> list[Path]:
    """Write fit.json, fitted.toml and (with ``plots``) fit.png to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"scene": scene.source, **result.as_dict()}
    write_json(out / "fit.json", summary)
    written = [out / "fit.json"]
    lines = [f"fitted by `tengfield fit` from {one_line(scene.source)} ({result.mode})"]
    for name in result.names:
        se = result.standard_errors[name]
        lines.append(f"{name} = {result.values[name]:.6g} +- {se:.3g}"
                     + ("" if result.identifiable[name] else "  (NOT identifiable)"))
    if "time_shift_s" in result.values:
        lines.append("time_shift_s is the trace's offset after the steady-window start "
                     "(no scene key)")
    write_text(out / "fitted.toml", scene_toml(fitted_scene_dict(scene, result),
                                               "\n".join(lines),
                                               base_dir=scene_dir(scene.source)))
    written.append(out / "fitted.toml")
    if plots:
        from ..plotting.fit import plot_fit
        written.append(plot_fit(result, out / figure_file("fit")))
    return written
