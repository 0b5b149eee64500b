"""Electrical outputs of a trajectory: the terminal, and the circuit on it.

* :mod:`.waveforms`: the waveform core (V_OC, Q_SC, I_SC with ``cells`` and C_p,
  the run's time axis, the steady window, the impacts, the one peak rule);
* :mod:`.circuits`: the circuit registry, one module per ``[circuit] kind``
  (``CIRCUITS``: open/short, load, rectifier, series-rc), each giving its
  columns, its waveforms, its stage text, its summary and array blocks;
* :mod:`.cycle`: energy per cycle (V-Q loops, the CMEO bound).

The names below are this package's face: ``from tengfield import electrical``
then ``electrical.terminal_peaks(...)``, ``electrical.steady_load(...)``.
"""
from .circuits import (CIRCUITS, Circuit, CircuitRun, SpreadCircuit, all_columns, circuit_for,
                       no_load)
from .circuits.load import LOAD_COLUMNS, LoadGrid, load_waveforms, relaxation_times, steady_load
from .circuits.rectifier import (CHUNK_VALUES, RECTIFIER_COLUMNS, concat_results,
                                 rectifier_grid, rectifier_summary, rectifier_waveforms)
from .circuits.rectifier_store import (NUMERICAL_DISSIPATION_WARN, check_store_resolution,
                                       first_crossing, harvester_options,
                                       smallest_resolved_store, warn_numerical_dissipation)
from .instrument import READ_COLUMNS, has_read, read_names
from .cycle import cmeo, cumulative, last_period, loop_area
from .waveforms import (IMPACT_OFFSET_PERIODS, PEAK_QUANTITIES, READ_COLUMN, WAVEFORM_COLUMNS,
                        elapsed_times, extreme_times, extremes, impact_elapsed, impact_states,
                        impact_times, peak_quantities, read_instrument, sample_elapsed, scene_terminal_waveforms,
                        scene_waveforms, steady_start, steady_window, steady_window_index,
                        terminal_extremes,
                        terminal_peaks, terminal_waveforms, terminal_waveforms_zr, time_origin,
                        trapezoid)

