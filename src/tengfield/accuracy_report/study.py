"""Error against run time for every stage, and the cheapest settings for a target accuracy.

``tengfield report [SCENE] -o DIR [--fast]`` (see ``docs/report.md``) runs
each stage of the pipeline at several accuracy levels and measures the
relative error of the *final waveforms* — the peak-to-peak open-circuit
voltage V_OC, short-circuit charge Q_SC and short-circuit current I_SC over
the steady window — against stated references:

* **field** (mesh size, degree, axisymmetric vs 3D, far-field treatment):
  every setting is solved at the same Chebyshev–Lobatto positions; the
  reference is the Richardson extrapolation (rate h⁴ of degree 2) of the two
  finest degree-2 axisymmetric Kelvin settings. A 3D row compares C and q at
  mid-stroke only (``error_position``), a 3D surrogate being too dear.
* **surrogate** (number of positions): nested Lobatto sets at the finest
  field setting against the largest set.
* **dynamics**: output sampling rate of the exact impact map against a
  much finer rate (the event location itself is exact to 1e-13 m and has
  no knob), and the soft contact of Eq. 1 at growing stiffness against the
  impact map (its rigid limit).
* **circuit**: the load ODE's step (the output sampling) for a stiff, a
  medium and a slow load, against a 16× finer step.

It then picks, for each target (1e-2, 1e-3), the cheapest combination whose
measured errors add up to at most the target, *runs it* (adaptive surrogate as
``tengfield run`` builds it, trajectory at the chosen rate) and states the
error it really reaches against the overall reference (largest surrogate at
the finest field setting, finest sampling). :func:`recommended_field_settings`
turns a tolerance into the ``[field]`` keys; :func:`scene_with_recommended`
applies them to the keys a scene file does not set.

All numbers are SI; errors are relative (|x − x_ref| / |x_ref|).

The settings and the plan live in :mod:`tengfield.accuracy_report.plan`, the
measurement of each stage in :mod:`tengfield.accuracy_report.stages`, the
recommendation logic in :mod:`tengfield.accuracy_report.recommend`; this module runs
them in order (:func:`build_report`) and verifies the recommendations.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

from .._args import checked_write
from .. import electrical
from .plan import (STAGE_TITLES, TARGETS, FieldSetting, Plan, make_plan, peak_errors,
                   solves_needed, stage_error_label)
from .recommend import Recommendation, recommend
from .stages import (_Solver, _trajectory, circuit_rows, dynamics_rows, field_rows,
                     planned_solves, surrogate_rows)


# ---------------------------------------------------------------------------
# the measurement
@dataclass
class Report:
    """Everything :func:`build_report` measured (``rows``) and recommends."""
    scene: Any
    plan: Plan
    rows: list
    recommendations: list
    references: dict
    trajectory: dict
    wall_time_s: float
    fast: bool

    @property
    def summary(self) -> dict:
        """JSON-ready: report.json's content."""
        import json
        import tempfile
        from pathlib import Path

        from ..io import write_report_json

        with tempfile.TemporaryDirectory() as tmp:
            path = write_report_json(Path(tmp) / "report.json", self)
            return json.loads(Path(path).read_text())

    @checked_write
    def write(self, out_dir, plots: bool = True) -> list:
        """Write what ``tengfield report -o out_dir`` writes; returns the paths (the stage
        PNGs are part of the report: ``plots`` is accepted for the common face)."""
        from .output import write_report

        return write_report(self, out_dir)

    def plot(self):
        """One matplotlib Figure, one panel per stage measured (the stage figures of
        :meth:`stage_figures`, side by side)."""
        import io

        import matplotlib.image as mpimg

        from ..plotting import new_figure, save_figure

        figures = self.stage_figures()
        fig = new_figure((5.5 * max(len(figures), 1), 4.5))
        axes = fig.subplots(1, max(len(figures), 1), squeeze=False)[0]
        for ax, (stage, stage_fig) in zip(axes, figures.items()):
            buffer = io.BytesIO()
            save_figure(stage_fig, buffer, dpi=100)
            buffer.seek(0)
            ax.imshow(mpimg.imread(buffer, format="png"))
            ax.set_title(stage)
        for ax in axes:
            ax.set_axis_off()
        return fig

    def stage_figures(self) -> dict:
        """The report's figures, one per stage measured: ``{"field": Figure, "surrogate":
        ..., "dynamics": ..., "circuit": ...}`` (matplotlib Figures, in that order; a
        stage without rows has none). Each is the error against wall time that
        ``tengfield report`` saves as ``<stage>.png``; a dict because the report has no
        single main figure (a notebook shows ``report.plot()["field"]``)."""
        from ..plotting.report import stage_figure   # the edge, imported on use

        figures = {}
        for stage, title in STAGE_TITLES.items():
            rows = [r for r in self.rows if r.stage == stage]
            if rows:
                figures[stage] = stage_figure(rows, stage, title, TARGETS,
                                              ylabel=stage_error_label(stage))
        return figures


def verify(recommendation: Recommendation, scene, reference_peaks, solver: "_Solver",
           farm_comm=None) -> Recommendation:
    """Run the recommended settings the way ``tengfield run`` does and measure them.

    The adaptive surrogate is built by :func:`tengfield.surrogate.precompute`
    with the recommended ``[field]`` keys (its ``tolerance`` decides how many
    positions); solves the report already did are reused (same setting and
    position, hence the same numbers), and the cost counted is the sum of the
    wall times of every solve the surrogate needed plus the dynamics. New solves
    are farmed over ``farm_comm``'s ranks (every rank gets the same table).
    """
    import warnings

    from ..surrogate import TerminalCurves, precompute

    f = recommendation.field
    setting = FieldSetting(method=f["method"], degree=f["degree"], mesh_size_mm=f["mesh_size_mm"],
                           far_field=f["far_field"], domain_radius_mm=f["domain_radius_mm"])

    def solve(_scene, z, comm=None):
        return solver.solve(setting, z)

    chosen = scene.with_values(**recommendation.scene_sections())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table = precompute(chosen, comm=farm_comm, solve=solve, solve_comm=solver.comm)
    dyn, dyn_wall, run_scene = _trajectory(chosen)
    wall = table.total_solve_wall_time + dyn_wall
    peaks = electrical.terminal_peaks(run_scene, dyn,
                                      TerminalCurves(table, chosen.circuit.reference,
                                                     chosen.device.ball_charge))
    errors = peak_errors(peaks, reference_peaks)
    worst = max(errors.values())
    return dataclasses.replace(recommendation, measured_error=worst, measured_errors=errors,
                               measured_wall_time_s=wall, positions=table.count,
                               reached=bool(worst <= recommendation.target))


def build_report(scene, *, fast: bool = False, comm=None, plan: Plan | None = None,
                 progress: bool = False, solve=None, farm_comm=None) -> Report:
    """``tf.report(scene)``: measure every stage of ``scene`` at several accuracy levels
    (see the module docstring); ``fast``: the CI-sized plan (``tengfield report --fast``).

    ``comm``: communicator of each field solve (default ``MPI.COMM_SELF``);
    ``solve``: the field solver (default :func:`tengfield.field.solve_position`,
    called as ``solve(scene, z, comm=..., estimate_error=False, **setting)``).
    ``farm_comm``: with several ranks (``mpirun -n N tengfield report``, the CLI
    passes ``COMM_WORLD``) the field solves, the trajectories of the dynamics
    and circuit stages and the verification solves are farmed over its ranks
    (:func:`tengfield._mpi.farm`); every rank returns the same rows and
    recommendations, whose errors equal a serial run's (wall times are measured
    on whichever rank ran the job).
    """
    from ..charge_models import check_command
    check_command(scene, "report")   # a charge model it runs
    from .._console import progress_bar
    from ..scene.parse import check_scene_argument

    check_scene_argument("tengfield.report", scene)
    if comm is None:
        from mpi4py import MPI
        comm = MPI.COMM_SELF
    plan = plan or make_plan(fast)
    started = time.perf_counter()
    total = _task_estimate(plan)
    bar = progress_bar(total, "report", progress, unit="task", comm=farm_comm)

    def advance(n=1):
        bar.update(n)

    solver = _Solver(scene, comm, solve=solve, progress=advance)
    trajectory, _, traj_scene = _trajectory(scene)
    solver.prefetch(planned_solves(solver, plan), farm_comm)
    rows, references = [], {}
    f_rows, f_ref = field_rows(solver, plan, traj_scene, trajectory)
    rows += f_rows
    references.update(f_ref)
    s_rows, ref_curves = surrogate_rows(solver, plan, traj_scene, trajectory)
    rows += s_rows
    references["surrogate"] = s_rows[0].reference
    d_rows, (_, _, overall_peaks) = dynamics_rows(plan, scene, ref_curves, advance, farm_comm)
    rows += d_rows
    references["dynamics"] = d_rows[0].reference
    rows += circuit_rows(plan, scene, ref_curves, advance, farm_comm)
    references["overall"] = (f"{plan.reference_count} Lobatto positions at "
                             f"{plan.reference_pair[1].label}, impact map sampled at "
                             f"{plan.reference_sample_rate:g} Hz")
    references["overall_peaks"] = overall_peaks
    recommendations = []
    for target in TARGETS:
        rec = recommend(rows, target)
        rec = verify(rec, scene, overall_peaks, solver, farm_comm)
        recommendations.append(rec)
        advance()
    bar.close()
    return Report(scene=scene, plan=plan, rows=rows, recommendations=recommendations,
                  references=references,
                  trajectory={"regime": getattr(trajectory.regime, "name", ""),
                              "sample_rate_hz": traj_scene.run.sample_rate},
                  wall_time_s=time.perf_counter() - started, fast=fast)


def _task_estimate(plan: Plan) -> int:
    field_solves = len(set(plan.field_settings + plan.far_field_settings)) * \
        solves_needed(plan.field_positions) + len(plan.settings_3d)
    surrogate_solves = solves_needed(plan.reference_count)
    # dynamics: the reference, each rate, the impact map at the run's rate, each stiffness;
    # circuit: per load the reference step and each step
    return (field_solves + surrogate_solves + len(plan.sample_rates) + len(plan.stiffnesses) + 2
            + len(plan.loads) * (len(plan.circuit_rates) + 1) + len(TARGETS))
