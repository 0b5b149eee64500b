"""Files of ``tengfield report``: report.md, one PNG per stage, recommended scene files.

Kept apart from :mod:`tengfield.accuracy_report.study` and the modules it runs (the
measurement: ``plan``, ``stages``, ``recommend``) so that the
measurement stays free of I/O and plotting; report.csv and report.json are
written by :mod:`tengfield.io`. Every file through :mod:`tengfield.files`.
"""
from __future__ import annotations

from pathlib import Path

from ..files import (figure_file, one_line, scene_dir, scene_toml, toml_value, write_figure,
                     write_text)
from ..io import format_number as _num
from ..terminals import of_scene
from ..io import write_report_csv, write_report_json
from .plan import (CIRCUIT_ERRORS, QUANTITIES, STAGE_TITLES, error_symbol, error_symbols,
                   error_words)



def scene_text(scene, sections: dict, header: str) -> str:
    """The whole scene as TOML with ``sections`` (file-level keys) replacing its values
    (an empty ``file``, no recorded excitation, left out)."""
    data = scene.to_dict()
    for sec, values in sections.items():
        data.setdefault(sec, {}).update(values)
    return scene_toml({sec: {k: v for k, v in values.items() if not (k == "file" and v == "")}
                       for sec, values in data.items()}, header,
                      base_dir=scene_dir(scene.source))


def table_row(cells) -> str:
    """One Markdown table row of ``cells``: a cell's ``|`` escaped and its line breaks as
    spaces, so that a note never adds a cell or ends the table."""
    return "| " + " | ".join(str(c).replace("|", "\\|").replace("\n", " ") for c in cells) + " |"


def markdown(report, images: dict) -> str:
    """The text of report.md."""
    sc = report.scene
    lines = [f"# tengfield report: error against run time{' (fast mode)' if report.fast else ''}",
             "",
             f"Scene: `{one_line(sc.source)}` — {sc.excitation.frequency:g} Hz, "
             f"A = {sc.excitation.amplitude * 1e3:g} mm, Δh = {sc.device.stroke * 1e3:g} mm, "
             f"d = {sc.device.ball_diameter * 1e3:g} mm, reference `{of_scene(sc).name}`; "
             f"regime {report.trajectory.get('regime', '?')}. Total wall time "
             f"{report.wall_time_s:.0f} s.",
             "",
             f"Errors are relative errors over the steady window, of the {error_words()} "
             "(`error_max` = the largest of these); for the circuit, of the "
             f"{error_words(CIRCUIT_ERRORS)}. Wall times are measured on this "
             "machine, which may be shared: they vary with its load.",
             "", "## References", ""]
    for key in ("field", "surrogate", "dynamics", "overall"):
        if key in report.references:
            lines.append(f"* **{key}**: {report.references[key]}")
    lines.append("* **soft contact**: the impact map (its rigid limit) at the same sampling")
    lines.append("* **circuit**: the same exponential integrator with a "
                 f"{report.plan.circuit_refinement}× finer step")
    for stage in ("field", "surrogate", "dynamics", "circuit"):
        rows = [r for r in report.rows if r.stage == stage]
        if not rows:
            continue
        lines += ["", f"## {STAGE_TITLES[stage]}", ""]
        if stage in images:
            lines += [f"![{stage}]({images[stage].name})", ""]
        if stage == "circuit":
            lines += ["| setting | τ = R C_T [s] | wall time [s] | "
                      + " | ".join(f"error {error_symbol(e)}" for e in CIRCUIT_ERRORS) + " |",
                      "|---|---|---|" + "---|" * len(CIRCUIT_ERRORS)]
            for r in rows:
                lines.append(table_row([r.setting, f"{r.knobs['time_constant_s']:.2g}",
                                        f"{r.wall_time_s:.3g}"]
                                       + [_num(r.errors.get(e)) for e in CIRCUIT_ERRORS]))
            continue
        extra = " | error C, q |" if stage == "field" else " |"
        head = ("| setting | wall time [s] | "
                + " | ".join(f"error {error_symbol(q)}" for q in QUANTITIES) + " | max" + extra)
        lines += [head, "|" + "---|" * (head.count("|") - 1)]
        for r in rows:
            entries = [r.setting, f"{r.wall_time_s:.3g}"]
            entries += [_num(r.errors.get(q)) for q in QUANTITIES]
            entries.append(_num(r.error))
            if stage == "field":
                entries.append(_num(r.error_position))
            lines.append(table_row(entries))
    lines += ["", "## Cheapest settings for a target accuracy", "",
              "Every combination of a measured field level, surrogate size and sampling rate "
              "competes; the cheapest one whose errors add up to at most the target is chosen. "
              "It is then *run* as `tengfield run` builds it (adaptive surrogate driven by "
              "`[field] tolerance`, which may refine beyond the chosen size) and measured "
              "against the overall reference.", "",
              "| target | [field] | sample_rate_hz | positions | predicted error | measured error "
              f"({error_symbols()}) | wall time [s] | reached | note |",
              "|---|---|---|---|---|---|---|---|---|"]
    for rec in report.recommendations:
        f = rec.field
        field_text = (f"{f['method']}, degree {f['degree']}, mesh {f['mesh_size_mm']:g} mm, "
                      f"{f['far_field']}, tolerance {f['tolerance']:g}")
        errs = ", ".join(_num(rec.measured_errors.get(q)) for q in QUANTITIES)
        lines.append(table_row([f"{rec.target:g}", field_text, f"{rec.sample_rate_hz:g}",
                                rec.positions, f"{rec.predicted_error:.2g}", errs,
                                f"{rec.measured_wall_time_s:.3g}",
                                "yes" if rec.reached else "NO", rec.note or ""]))
    lines += ["", "Use them: `tengfield run recommended-0.001.toml` (this scene with the block "
              "below), or in Python "
              "`tengfield.accuracy_report.recommended_field_settings(tolerance)`.", ""]
    for rec in report.recommendations:
        lines += [f"```toml\n# target {rec.target:g}", "[field]"]
        lines += [f"{k} = {toml_value(v)}" for k, v in rec.field.items()]
        lines += ["[run]", f"sample_rate_hz = {toml_value(rec.sample_rate_hz)}", "```", ""]
    return "\n".join(lines)


def write_report(report, out_dir) -> list[Path]:
    """Write report.csv, report.json, report.md, one PNG per stage and
    ``recommended-<target>.toml`` scene files to ``out_dir`` (each atomically)."""
    from ..plotting import save_figure

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_report_csv(out / "report.csv", report),
               write_report_json(out / "report.json", report)]
    images = {}
    for stage, fig in report.stage_figures().items():    # the figures a notebook gets
        images[stage] = write_figure(save_figure, fig, dpi=100, path=out / figure_file(stage))
        written.append(images[stage])
    for rec in report.recommendations:
        path = out / f"recommended-{rec.target:g}.toml"
        write_text(path, scene_text(report.scene, rec.scene_sections(),
                                   f"{one_line(report.scene.source)} with the cheapest settings measured by "
                                   f"`tengfield report`\nto reach {rec.target:g} on the peak-to-peak "
                                   f"{error_symbols()} (measured: {rec.measured_error:.2g})"))
        written.append(path)
    md = out / "report.md"
    write_text(md, markdown(report, images))
    written.append(md)
    return written

