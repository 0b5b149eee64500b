"""The figures of a rectifier's store and of an ``[array]``: charging.png
(:class:`~tengfield.harvest.HarvestResult`) and array.png
(:class:`~tengfield.array.ArrayResult`), as ``tengfield run`` draws them; every file
through :mod:`tengfield.files`."""
from __future__ import annotations

from pathlib import Path

from ..files import figure_file, write_figure


def _scene_of(result, scene):
    scene = scene if scene is not None else getattr(result, "scene", None)
    if scene is None:
        raise ValueError(f"{type(result).__name__}.write needs its scene (the [circuit] and "
                         "[array] it ran with): pass scene=..., or take the result from "
                         "tengfield.run")
    return scene


def write_charging_figure(fine, out_dir, *, scene=None, title: str = "",
                          figures=None) -> Path:
    """charging.png: the store voltage U(t) of ``fine`` (a HarvestResult) with the UVLO
    levels of ``scene``'s chip (default ``fine.scene``)."""
    from ..plotting.harvest import plot_charging

    return write_figure(plot_charging, fine, _scene_of(fine, scene),
                        path=Path(out_dir) / figure_file("charging"), figures=figures,
                        title=title)


def write_array_figure(array, out_dir, *, summary: dict | None = None, title: str = "",
                       figures=None) -> Path:
    """array.png: the cells' phases and the array against N x one cell (``summary``: the
    run's ``array`` block, default ``array.summary``)."""
    from ..plotting.harvest import plot_array

    return write_figure(plot_array, array, array.summary if summary is None else summary,
                        path=Path(out_dir) / figure_file("array"), figures=figures, title=title)


def write_harvest_files(fine, out_dir, *, plots: bool = True, scene=None,
                        title: str = "") -> list[Path]:
    """What ``tengfield run`` writes of a rectifier's store record: charging.png (with
    ``plots``; its numbers are columns of waveforms.csv and summary.json's ``rectifier``
    block, written with the run)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [write_charging_figure(fine, out, scene=scene, title=title)] if plots else []


def write_array_files(array, out_dir, *, plots: bool = True, title: str = "") -> list[Path]:
    """What ``tengfield run`` writes of an ``[array]`` beside the run's tables: array.png
    (with ``plots``; the array's numbers are summary.json's ``array`` block)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [write_array_figure(array, out, title=title)] if plots else []
