"""The spherical shell against the paper's tube: the same PTFE ball, the same free stroke.

A ball bouncing inside a spherical cavity whose two hemispheres are the electrodes
(``[device] shape = "spherical-shell"``, docs/spherical_shell.md) against the paper's
tube between two flat electrodes (the default scene): the same 7 mm PTFE ball (σ =
−8 µC/m², 2200 kg/m³), the same 3 mm of free travel along the drive's axis (a 10 mm
cavity), the same wall material (ε = 2.6, 1.5 mm of shell as the tube's wall) and the
same vertical vibration (the paper's 1.5 mm at 20 Hz). For each cell: V_OC, Q_SC, I_SC
(peak and peak-to-peak over the steady window), the terminal capacitance C_T, the
air-breakdown limit σ_max (``tengfield breakdown``) and the output at σ = −σ_max.

Then the shell under 3-axis vibration (``shell-3axis``): the same 1.5 mm / 20 Hz
vertical drive plus 1.5 mm along x and y (90° apart, a circular table motion), the ball
in 3D (``[contact] model = "3d"``: Hertz contact on the spherical wall, friction, spin),
rolling and bouncing around the cavity; its field is the shell's (z, r) surrogate
anchored on the axisymmetric one (fast: P1 at 4 mm to 5 % on a 5 x 3 grid; full: the
default P2 at 1.5 mm).
Writes ``spherical_shell.png`` (Q_SC(z) and C_T(z) of both cells on the axis; Q_SC(t)
and V_OC(t) over two periods, all three runs).

    .venv/bin/python demos/spherical_shell.py [--fast] [-o DIR] [--cache-dir DIR]
"""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from electrical_common import (demo_arguments, field_settings, paper_scene,  # noqa: E402
                               pyplot, run_length, save_small_png)
from demo_mpi import is_root, world  # noqa: E402

#: the shell: the paper's ball in a cavity giving the tube's 3 mm stroke (mm)
SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 10.0, "shell_thickness_mm": 1.5,
         "electrode_band_mm": 1.0}


def scenes(fast: bool) -> dict:
    """The two scenes at the paper's 1.5 mm / 20 Hz (tube: the default scene)."""
    tube = paper_scene(fast).with_values(
        excitation={"frequency_hz": 20.0, "amplitude_mm": 1.5}, run=run_length(20.0, fast))
    from tengfield.scene import Scene
    raw = {sec: dict(values) for sec, values in tube.raw.items()}
    device = {k: v for k, v in raw["device"].items()
              if k not in ("stroke_mm", "electrode_radius_mm", "tube_inner_radius_mm",
                           "tube_outer_radius_mm", "plate_thickness_mm")}
    raw["device"] = {**device, **SHELL}
    raw["field"] = {**raw.get("field", {}), **field_settings(fast)}
    shell = Scene.from_dict(raw)
    three_axis = shell.with_values(
        contact={"model": "3d"},
        excitation={"amplitude_x_mm": 1.5, "amplitude_y_mm": 1.5,
                    "phase_x_deg": 0.0, "phase_y_deg": 90.0})
    return {"tube": tube, "shell": shell, "shell-3axis": three_axis}


def radial_settings(fast: bool) -> dict:
    """The (z, r) surrogate's settings: full the default (P2, 1.5 mm, 1e-2); fast P1 at
    4 mm to 5 %, starting from 3 heights instead of 9: its first refinement, a 5 x 3 grid
    of 3D solves (the ball's z-dependence is the axisymmetric table's, the 3D solves give
    only its change with r), is already within the 5 % (0.42 nC as with 17 x 3; 0.44 nC
    with a 3 mm table of 33 x 9). The 3D meshing is most of the demo's time."""
    return ({"mesh_size_mm": 4.0, "degree": 1, "tolerance": 0.05, "initial_positions": 3}
            if fast else {})


def outputs(scene, cache_dir, fast: bool = True) -> dict:
    """``tengfield run`` of ``scene``: the peaks, C_T, the surrogate's curves and the
    waveforms; then at σ = "breakdown": σ_max and the peaks there."""
    from tengfield.pipeline import run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        settings = radial_settings(fast)
        r = run(scene, cache_dir=cache_dir, comm=world(), radial_settings=settings)
        limit = run(scene.with_values(device={"surface_charge_uC_per_m2": "breakdown"}),
                    cache_dir=cache_dir, comm=world(), radial_settings=settings)
    z = np.linspace(0.0, scene.device.stroke, 121)
    axis = getattr(r.curves, "axis", r.curves)    # a 3D run's curves: the axis + the r change
    lateral = {}
    if "field_zr" in r.stages:
        motion = r.dynamics.summary
        lateral = {"max_radial_offset_mm": motion["max_radial_offset_mm"],
                   "mean_radial_offset_mm": motion["mean_radial_offset_mm"],
                   "zr_grid": r.stages["field_zr"].details["grid"]}
    block = limit.summary["breakdown"]
    return {"peak": {k: r.peak[k] for k in ("V_oc", "Q_sc", "I_sc")},
            "peak_to_peak": {k: r.peaks[k] for k in ("V_oc", "Q_sc", "I_sc")},
            "C_T_pF": [float(np.min(axis.capacitance(z))) * 1e12,
                       float(np.max(axis.capacitance(z))) * 1e12],
            "Q_sc_full_stroke_nC": abs(float(axis.charge(z[-1]) - axis.charge(z[0]))) * 1e9,
            "max_gap_mm": r.summary["regime"]["max_gap_m"] * 1e3,
            "regime": r.summary["regime"]["regime"],
            "sigma_max_uC_per_m2": block["sigma_max_uC_per_m2"],
            "sigma_max_error": block["relative_error_estimate"],
            "at_sigma_max_peak_to_peak": {k: limit.peaks[k] for k in ("V_oc", "Q_sc", "I_sc")},
            "volume_cm3": scene.device.cell_volume * 1e6,
            **lateral,
            "_curves": (z, axis), "_waves": (r.t, r.Q_sc, r.V_oc, scene.excitation.period)}


def figure(results: dict, path: Path) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    for name, res in results.items():
        z, curves = res["_curves"]
        if name != "shell-3axis":   # its axis curves are the shell's
            axes[0, 0].plot(z * 1e3, (curves.charge(z) - curves.charge(0.0)) * 1e9, label=name)
            axes[0, 1].plot(z * 1e3, curves.capacitance(z) * 1e12, label=name)
        t, q, v, period = res["_waves"]
        window = t >= t[-1] - 2.0 * period
        axes[1, 0].plot((t[window] - t[window][0]) * 1e3, q[window] * 1e9, label=name)
        axes[1, 1].plot((t[window] - t[window][0]) * 1e3, v[window], label=name)
    labels = (("gap z [mm]", "Q_SC(z) - Q_SC(0) [nC]"), ("gap z [mm]", "C_T [pF]"),
              ("time [ms]", "Q_SC [nC]"), ("time [ms]", "V_OC [V]"))
    for ax, (xl, yl) in zip(axes.flat, labels):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle("spherical shell (10 mm cavity) vs the paper's tube: 7 mm PTFE ball, "
                 "3 mm stroke, 1.5 mm / 20 Hz, sigma = -8 uC/m^2")
    fig.tight_layout()
    save_small_png(fig, path)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict:
    args = demo_arguments(__doc__, argv)
    out = Path(args.output)
    results = {name: outputs(scene, args.cache_dir, args.fast)
               for name, scene in scenes(args.fast).items()}
    figure(results, out / "spherical_shell.png")
    numbers = {name: {k: v for k, v in res.items() if not k.startswith("_")}
               for name, res in results.items()}
    if is_root():
        print("the spherical shell against the paper's tube (same ball, same 3 mm stroke, "
              "1.5 mm / 20 Hz, sigma = -8 uC/m^2)")
        for name, res in numbers.items():
            pk, pp, lim = res["peak"], res["peak_to_peak"], res["at_sigma_max_peak_to_peak"]
            print(f"  {name:11s}: V_OC {pk['V_oc']:.4g} V (pp {pp['V_oc']:.4g}), Q_SC "
                  f"{pk['Q_sc'] * 1e9:.4g} nC (pp {pp['Q_sc'] * 1e9:.4g}), I_SC "
                  f"{pk['I_sc'] * 1e9:.4g} nA (pp {pp['I_sc'] * 1e9:.4g}); C_T "
                  f"{res['C_T_pF'][0]:.3g}-{res['C_T_pF'][1]:.3g} pF; max gap "
                  f"{res['max_gap_mm']:.3g} mm ({res['regime']})")
            print(f"         sigma_max = {res['sigma_max_uC_per_m2']:.3g} uC/m^2 "
                  f"(+-{100 * res['sigma_max_error']:.2g} %): pp V_OC {lim['V_oc']:.4g} V, "
                  f"Q_SC {lim['Q_sc'] * 1e9:.4g} nC, I_SC {lim['I_sc'] * 1e9:.4g} nA; "
                  f"volume {res['volume_cm3']:.3g} cm^3")
            if "max_radial_offset_mm" in res:
                print(f"         off the axis: up to {res['max_radial_offset_mm']:.3g} mm "
                      f"(mean {res['mean_radial_offset_mm']:.3g} mm); (z, r) grid "
                      f"{res['zr_grid'][0]} x {res['zr_grid'][1]}")
        ratio = numbers["shell"]["peak_to_peak"]["Q_sc"] / numbers["tube"]["peak_to_peak"]["Q_sc"]
        print(f"  Q_SC shell / tube = {ratio:.3g} (the paper's tube device: 1.42 nC measured "
              "at its fitted sigma)")
        print(f"wrote {out / 'spherical_shell.png'}")
    return numbers


if __name__ == "__main__":
    main()
