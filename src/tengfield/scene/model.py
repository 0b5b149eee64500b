"""The scene objects (SI values only: metres, seconds, coulombs...) and their
construction from file-level values.

Every dataclass checks itself against :data:`tengfield.scene.schema.SCHEMA` when
built, from a file or from Python (``Device(ball_diameter=-1, ...)`` raises a
:class:`SceneError` naming the key and its range); cross-section rules (the initial gap
within the stroke, the work limits, the array against the circuit) are checked by
:class:`Scene`. :func:`build` turns a parsed scene (file keys, file units) into a
:class:`Scene`, reading the files it names (recorded excitation, PSD table).
"""
from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..paschen import STREAMER_PD
from .constants import G
from .limits import (RefusedField as _RefusedField, auto_domain_radius, check_array_work,
                     check_ensemble_work,
                     check_steady_window, check_vibration_work, check_work, field_problems,
                     show_number)
from .recorded import read_psd, read_recorded
from .shapes import (NUMERIC_SIGMA, check_shape_scene, gap_lines_problem, shape_field_inputs,
                     shape_field_problems, shape_of)
from .schema import (AUTO_KEYS, FIELD_KEYS, FIELD_SCHEMA, HASH_NAMES, PASSTHROUGH_SECTIONS,
                     SCHEMA, check_section, convert, harmonic_components, suggest,
                     update_section, with_defaults)
from .schema import renamed as _renamed
from .schema import show
from .._mpi import launched_rank as _launched_rank
from .schema import SURFACE_CHARGE_KEY


@dataclass(frozen=True)
class Device:
    """Geometry and materials, SI. The z axis is the tube axis."""
    ball_diameter: float        # [m]
    stroke: float               # free stroke dh = h - d [m] (scene key stroke_mm)
    electrode_radius: float     # [m]
    tube_inner_radius: float    # [m]
    tube_outer_radius: float    # [m] (= end-plate radius)
    plate_thickness: float      # [m]
    ball_density: float         # [kg/m^3]
    ball_permittivity: float    # relative
    wall_permittivity: float    # relative
    surface_charge: float       # [C/m^2], negative for PTFE
    cells: int
    # 3D motion: gravity tilted by ``tilt`` from -z toward azimuth ``tilt_azimuth`` [rad]
    tilt: float = 0.0
    tilt_azimuth: float = 0.0
    # the cell's shape and the spherical shell's keys (scene/shapes/) [m]
    shape: str = "tube"
    cavity_diameter: float = 20e-3
    shell_thickness: float = 2e-3
    electrode_band: float = 2e-3
    # "both" (the electrode pair) or "lower" (the single-electrode cell, issue #51)
    electrodes: str = "both"

    def __post_init__(self):
        check_section("device", self, "Device")
        shape_of(self.shape).check(self)   # the shape's own rules (the tube's: ball fits)
        offered = getattr(shape_of(self.shape), "electrode_sets", ("both",))
        if self.electrodes not in offered:
            raise SceneError(f"[device] electrodes = {self.electrodes!r} is not offered by "
                             f"shape = {self.shape!r} yet: allowed "
                             + ", ".join(repr(e) for e in offered))

    @property
    def electrode_names(self) -> tuple[str, ...]:
        """The cell's electrodes, in the order of the field's matrices: ``("lower",
        "upper")`` for the pair, ``("lower",)`` for the single-electrode cell."""
        return ("lower",) if self.electrodes == "lower" else ("lower", "upper")

    @property
    def ball_radius(self) -> float:
        return 0.5 * self.ball_diameter

    @property
    def plate_spacing(self) -> float:
        """h = d + dh: distance between the electrode faces [m]."""
        return self.ball_diameter + self.stroke

    @property
    def ball_mass(self) -> float:
        return self.ball_density * math.pi * self.ball_diameter**3 / 6.0

    @property
    def ball_charge(self) -> float:
        """Total charge on the ball, sigma * pi d^2 [C]."""
        return self.surface_charge * math.pi * self.ball_diameter**2

    @property
    def bounding_radius(self) -> float:
        """Radius of the smallest sphere about the device centre holding one cell [m]."""
        return shape_of(self.shape).bounding_radius(self)

    @property
    def longest_path(self) -> float:
        """The longest discharge path [m] between the ball and an electrode (Paschen's
        low-pressure bound; each shape's own, scene/shapes/)."""
        return shape_of(self.shape).longest_path(self)

    @property
    def cell_volume(self) -> float:
        """Outer volume of one cell [m^3]: tube and both plates, or the shell's sphere."""
        return shape_of(self.shape).volume(self)


@dataclass(frozen=True)
class Excitation:
    """Table motion y(t): ``A sin(2 pi f t + phase)``, a recorded signal, harmonics or
    random noise."""
    kind: str
    frequency: float            # [Hz]; for "recorded" used as the reference period
    amplitude: float            # [m]
    phase: float                # [rad]
    file: str
    time_column: str
    signal_column: str
    signal: str
    times: np.ndarray | None = field(default=None, compare=False, repr=False)   # [s]
    values: np.ndarray | None = field(default=None, compare=False, repr=False)  # [m] or [m/s^2]
    # 3D motion: lateral sine x = A_x sin(w t + phase_x) [m, rad]; recorded columns
    # (read with the signal: values_x, values_y, same unit as values)
    amplitude_x: float = 0.0
    amplitude_y: float = 0.0
    phase_x: float = 0.0
    phase_y: float = 0.0
    signal_x_column: str = ""
    signal_y_column: str = ""
    header_row: int = 0         # the CSV's header line (1-based); 0: found (issue #39)
    smoothing: float = 0.0      # [Hz] zero-phase low-pass of a recorded signal, 0 = off
    # random and harmonics (issue #25): components (frequency [Hz], amplitude [m],
    # phase [rad]); noise PSD: a flat band [Hz] with rms_acceleration [m/s^2], or a
    # table (psd_frequencies [Hz], psd_values [(m/s^2)^2/Hz]); seed of the realisation
    acceleration: float = 0.0
    band: tuple = ()
    rms_acceleration: float = 0.0
    psd_file: str = ""
    seed: int = 0
    rms_acceleration_x: float = 0.0
    rms_acceleration_y: float = 0.0
    harmonics: tuple = ()
    psd_frequencies: np.ndarray | None = field(default=None, compare=False, repr=False)
    psd_values: np.ndarray | None = field(default=None, compare=False, repr=False)
    values_x: np.ndarray | None = field(default=None, compare=False, repr=False)
    values_y: np.ndarray | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        check_section("excitation", self, "Excitation")
        band, psd_file = self.band, self.psd_file   # the noise of random / harmonics
        levels = (("rms_acceleration_m_per_s2", self.rms_acceleration),
                  ("rms_acceleration_x_m_per_s2", self.rms_acceleration_x),
                  ("rms_acceleration_y_m_per_s2", self.rms_acceleration_y))
        if self.kind not in ("random", "harmonics"):
            for key, given in (("band_hz", band), ("psd_file", psd_file)):
                if given:
                    raise SceneError(f"[excitation] {key} needs kind = 'random' or 'harmonics' "
                                     f"(kind = {self.kind!r})")
            for key, level in levels:   # a noise level would be silently left out
                if level > 0.0:
                    raise SceneError(f"[excitation] {key} = {level:g} needs kind = 'random' or "
                                     f"'harmonics' (kind = {self.kind!r}) with band_hz or "
                                     "psd_file: a noise level without noise")
            return
        if band and psd_file:
            raise SceneError("[excitation] band_hz and psd_file: give one of them (a flat band "
                             "or a PSD table)")
        if band:
            if len(band) != 2 or not band[0] < band[1]:
                shown = ", ".join(f"{b:g}" for b in band)
                raise SceneError(f"[excitation] band_hz = [{shown}]: expected [f1, f2] with "
                                 "0 < f1 < f2 [Hz]")
            if self.rms_acceleration <= 0.0:
                raise SceneError("[excitation] band_hz needs rms_acceleration_m_per_s2 > 0 "
                                 f"(it is {self.rms_acceleration:g})")
        elif not psd_file and self.kind == "random":
            raise SceneError("[excitation] kind = 'random' needs band_hz = [f1, f2] with "
                             "rms_acceleration_m_per_s2, or psd_file = 'name.csv'")
        elif not psd_file:   # harmonics without noise: a noise level would be left out
            for key, level in levels:
                if level > 0.0:
                    raise SceneError(f"[excitation] {key} = {level:g} needs band_hz = [f1, f2] "
                                     "or psd_file = 'name.csv' (the noise's spectrum): "
                                     "kind = 'harmonics' has no noise without one")

    @property
    def has_noise(self) -> bool:
        """Random noise is part of the table motion (kind random, or harmonics + noise)."""
        return self.kind in ("random", "harmonics") and (bool(self.band) or bool(self.psd_file))

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.frequency

    @property
    def period(self) -> float:
        return 1.0 / self.frequency

    @property
    def gamma(self) -> float:
        """Dimensionless intensity A w^2 / g (sine only)."""
        return self.amplitude * self.omega**2 / G


@dataclass(frozen=True)
class Contact:
    model: str
    restitution: float
    restitution_model: str
    restitution_reference_speed: float   # [m/s]
    restitution_exponent: float
    stiffness: float                     # [N/m]
    # 3D motion, SI: moduli [Pa], damping [N s/m] (< 0: from restitution), penetration_max [m]
    law: str = "hertz"
    damping_model: str = "calibrated"   # Hertz: beta fitted to rebound with e, or Chrono's closed form
    exponent: float = 1.0
    damping: float = -1.0
    penetration_max: float = 0.0
    ball_youngs_modulus: float = 0.5e9
    ball_poisson_ratio: float = 0.46
    plate_youngs_modulus: float = 120e9
    plate_poisson_ratio: float = 0.34
    wall_youngs_modulus: float = 3.0e9
    wall_poisson_ratio: float = 0.37
    friction_static: float = 0.1
    friction_dynamic: float = 0.05

    def __post_init__(self):
        check_section("contact", self, "Contact")

    def restitution_at(self, speed: float) -> float:
        """Restitution for an impact at relative speed ``speed`` [m/s].

        "constant": e. "power-law": ``min(1, e (v/v_ref)^-p)``, a common fit of
        velocity-dependent restitution of polymer balls (e falls with speed).
        """
        if self.restitution_model == "constant" or self.restitution_exponent == 0.0:
            return self.restitution
        v = max(abs(speed), 1e-12)
        return min(1.0, self.restitution * (v / self.restitution_reference_speed) ** (-self.restitution_exponent))


@dataclass(frozen=True)
class Initial:
    time: float       # [s]
    gap: float        # [m]
    velocity: float   # relative to the table [m/s]

    def __post_init__(self):
        check_section("initial", self, "Initial")


@dataclass(frozen=True)
class Run:
    duration: float        # [s]
    settle_periods: int
    sample_rate: float     # [Hz]
    realisations: int = 1  # independent seeds of a random excitation
    output_format: str = "csv"   # "csv" | "hdf5" (tengfield.files.hdf5; auto past the CSV bound)

    def __post_init__(self):
        check_section("run", self, "Run")


@dataclass(frozen=True)
class Field:
    method: str
    degree: int
    mesh_size: float       # [m]
    tolerance: float
    domain_radius: float   # [m]
    environment: str
    far_field: str
    ball_offset: float     # [m]
    max_memory_gb: float = 0.0       # one solve's estimated peak; 0: 80 % of the machine
    radial_mesh_size: float = 1.5e-3  # [m] the (z, r) surrogate's 3D solves
    radial_degree: int = 2
    radial_tolerance: float = 1e-2
    mesh_motion: str = "remesh"       # "move": one mesh per table moved with the ball
    mesh_grading: str = "uniform"     # 3D meshes: "graded" coarsens away from gaps, rims, ball

    def __post_init__(self):
        check_section("field", self, "Field")


@dataclass(frozen=True)
class Circuit:
    kind: str
    load: float                   # [ohm]
    parallel_capacitance: float   # [F]
    reference: str
    # harvesting (kind = "rectifier"; tengfield.harvest), SI
    diode: str = "ideal"
    diode_forward_voltage: float = 0.0         # [V] per diode (ideal model)
    diode_saturation_current: float = 1e-12    # [A] (shockley)
    diode_emission_coefficient: float = 1.0    # (shockley)
    diode_series_resistance: float = 0.0       # [ohm] per diode
    storage_capacitance: float = 10e-6         # [F]
    storage_leakage: float = 0.0               # [ohm], 0: none
    pmic: str = "none"
    uvlo_rising: float = 5.05                  # [V]
    uvlo_falling: float = 4.04                 # [V]
    pmic_output: float = 3.3                   # [V]
    pmic_load: float = 1e5                     # [ohm]
    pmic_efficiency: float = 0.9
    pmic_quiescent_current: float = 450e-9     # [A]
    pmic_shunt: float = 20.0                   # [V]
    series_capacitance: float = 100e-12        # [F] (kind = "series-rc")

    def __post_init__(self):
        check_section("circuit", self, "Circuit")
        if self.uvlo_rising <= self.uvlo_falling:
            raise SceneError(f"[circuit] uvlo_rising_V = {self.uvlo_rising:g} must exceed "
                             f"uvlo_falling_V = {self.uvlo_falling:g} (the lockout's hysteresis)")
        if self.pmic_output >= self.uvlo_falling:
            raise SceneError(f"[circuit] pmic_output_V = {self.pmic_output:g} is out of range: "
                             f"allowed (0, {self.uvlo_falling:g}) (below uvlo_falling_V)")
        if self.pmic_shunt <= self.uvlo_rising:
            raise SceneError(f"[circuit] pmic_shunt_V = {self.pmic_shunt:g} must exceed "
                             f"uvlo_rising_V = {self.uvlo_rising:g}")


@dataclass(frozen=True)
class Array:
    """``[array]``: ``cells`` (0: none), ``connection``, spreads (full widths:
    ``phase_spread`` [rad], ``restitution_spread``, ``velocity_spread`` [m/s]), ``seed``."""
    cells: int = 0
    connection: str = "parallel"
    phase_spread: float = 0.0
    restitution_spread: float = 0.0
    velocity_spread: float = 0.0
    seed: int = 0

    def __post_init__(self):
        check_section("array", self, "Array")
        if self.cells == 0 and (self.phase_spread or self.restitution_spread
                                or self.velocity_spread or self.connection != "parallel"):
            raise SceneError("[array] spreads and connection need [array] cells >= 1")


@dataclass(frozen=True)
class Breakdown:
    """``[breakdown]``: ``pressure`` [Pa], Paschen's ``paschen_A`` [1/(Pa m)],
    ``paschen_B`` [V/(Pa m)], ``gamma`` (γ, secondary emission) and ``gamma_range`` (the
    band's γ), ``paschen`` (the curve), the seed-limited estimate's ``seed_rate``
    S_v [1/(m^3 s)], ``ion_density`` n_ion [1/m^3] and ``breakdowns_per_s`` [1/s]."""
    pressure: float = 101325.0
    paschen_A: float = 11.25
    paschen_B: float = 273.75
    gamma: float = 0.01
    gamma_range: tuple = (1e-4, 0.1)
    paschen: str = "townsend"
    seed_rate: float = 1e7
    ion_density: float = 5e8
    breakdowns_per_s: float = 1.0

    @property
    def secondary_emission(self) -> float:
        """γ under its name before issue #38."""
        return self.gamma

    def __post_init__(self):
        check_section("breakdown", self, "Breakdown")
        if len(self.gamma_range) != 2 or not self.gamma_range[0] <= self.gamma_range[1]:
            raise SceneError(f"[breakdown] gamma_range = {list(self.gamma_range)}: allowed two "
                             "numbers [low, high] with 0 < low <= high <= 1")
        # the Townsend range must not be empty for any γ used (the scene's, the range's)
        gamma = min(self.gamma, *self.gamma_range)
        lowest = math.exp(1.0 + math.log(math.log1p(1.0 / gamma))) / STREAMER_PD
        if self.paschen_A <= lowest:
            raise SceneError(f"[breakdown] paschen_A_per_Pa_m = {self.paschen_A:g} is out of range "
                             f"with gamma = {gamma:g}: allowed "
                             f"({lowest:.4g}, 10000] (Paschen's minimum must lie below the "
                             f"streamer regime, p d = {STREAMER_PD:.4g} Pa m)")


@dataclass(frozen=True)
class Charge:
    """``[charge]``: how the ball gets its charge (:mod:`tengfield.source`,
    docs/charge.md). ``model``: "constant" ([device] surface_charge), "breakdown" (its
    air-breakdown limit) or "contact" (impact by impact); for "contact" ``equilibrium``
    sigma_eq [C/m^2] (signed), ``efficiency`` eta in (0, 1], ``initial`` sigma at the start
    [C/m^2], ``leakage_time`` tau [s] (0: none) and ``discharge``, the air-breakdown level
    that caps |sigma| ("estimate", "lower", "upper" of the band, "static": sigma_max at
    [breakdown] gamma, "none")."""
    model: str = "constant"
    equilibrium: float = -113e-6
    efficiency: float = 1.0
    initial: float = 0.0
    leakage_time: float = 0.0
    discharge: str = "estimate"
    #: relative humidity in [0, 1] (the file's percent / 100): sigma_eq, tau and Paschen's
    #: B follow :mod:`tengfield.humidity`'s assumed law; 0 = dry, the constants as given
    relative_humidity: float = 0.0
    #: what the electrical stage covers: "auto", "steady" (the last settle_periods +
    #: window_periods excitation periods of the run) or "start-up" (the whole run)
    waveforms: str = "auto"
    window_periods: int = 50

    def __post_init__(self):
        check_section("charge", self, "Charge")

    @property
    def from_contacts(self) -> bool:
        """The contacts make the charge (the model's entry in
        :data:`tengfield.charge_models.CHARGE_MODELS`: ``"contact"``)."""
        from ..charge_models import charge_model
        return charge_model(self.model).from_contacts


@dataclass(frozen=True)
class Instrument:
    """``[instrument]``: what the bench's electrometer or scope records (SI; 0 means none
    for each, :mod:`tengfield.electrical.instrument`): ``capacitance`` C_p [F] across the
    terminals, ``input_resistance`` R_in [ohm] (0: infinite), ``bandwidth`` [Hz] of a
    first-order analog low-pass (0: unlimited), ``aperture`` [s] the integration time of
    one reading (0: instantaneous), ``sample_rate`` [Hz] of the readings (0: one per output
    sample). ``given``: the scene has the section (without it no read quantity but the
    deprecated ``[circuit] parallel_capacitance_pF``'s ``V_read_V`` exists)."""
    capacitance: float = 0.0
    input_resistance: float = 0.0
    bandwidth: float = 0.0
    aperture: float = 0.0
    sample_rate: float = 0.0
    given: bool = False

    def __post_init__(self):
        check_section("instrument", self, "Instrument")

    @property
    def ideal(self) -> bool:
        """No bandwidth limit, no aperture, a reading at every sample, no input resistance:
        the read quantities are the terminal's own (V through C_p)."""
        return (self.bandwidth == 0.0 and self.aperture == 0.0 and self.sample_rate == 0.0
                and self.input_resistance == 0.0)


@dataclass(frozen=True)
class Reference:
    """``[reference]``: measured values [SI] to compare the run with (0: not given):
    ``V_pp``, ``V_peak`` [V], ``Q_pp``, ``Q_peak`` [C], ``I_pp``, ``I_peak`` [A],
    ``P_mean`` [W]. Which tool quantity each is compared with:
    :data:`tengfield.quantities.MEASURED`."""
    V_pp: float = 0.0
    V_peak: float = 0.0
    Q_pp: float = 0.0
    Q_peak: float = 0.0
    I_pp: float = 0.0
    I_peak: float = 0.0
    P_mean: float = 0.0

    def __post_init__(self):
        check_section("reference", self, "Reference")

    def given(self) -> dict[str, float]:
        """``{file key: measured value [SI]}`` of the values given (non-zero)."""
        return {key: getattr(self, spec.attr) for key, spec in SCHEMA["reference"].items()
                if getattr(self, spec.attr) != 0.0}


@dataclass(frozen=True)
class Scene:
    """One BB-TENG and how it is driven: the sections as SI dataclasses, the file-level
    values as given (``raw``), where they came from (``source``, ``text``, and the
    ``--set`` settings applied to it in order, ``settings``: what teng.lib's header names)."""
    device: Device
    excitation: Excitation
    contact: Contact
    initial: Initial
    run: Run
    field: Field
    circuit: Circuit
    array: Array = Array()
    breakdown: Breakdown = Breakdown()
    reference: Reference = Reference()
    instrument: Instrument = Instrument()
    charge: Charge = Charge()
    raw: dict = dataclasses.field(compare=False, repr=False, default_factory=dict)
    source: str = dataclasses.field(compare=False, repr=False, default="<default>")
    text: str = dataclasses.field(compare=False, repr=False, default="")
    settings: tuple = dataclasses.field(compare=False, repr=False, default=())

    def __post_init__(self):
        """The rules between sections (the field's are checked by :func:`check_field`)."""
        dev, exc, run, arr = self.device, self.excitation, self.run, self.array
        if self.initial.gap > dev.stroke:
            raise SceneError(f"[initial] gap_mm = {show_number(self.initial.gap * 1e3, dev.stroke * 1e3)}"
                             " is out of range: "
                             f"allowed [0, {dev.stroke * 1e3:g}] (the free stroke [device] stroke_mm)")
        if dev.electrodes == "lower" and self.circuit.reference != "floating":
            raise SceneError(f"[circuit] reference = {self.circuit.reference!r} with [device] "
                             "electrodes = 'lower': the single-electrode cell has one "
                             "topology, the electrode to the ground (leave reference out)")
        check_steady_window(exc, run.settle_periods, run.duration)
        # a contact run's waveforms may cover only its last periods (contact_run)
        charge = self.charge
        check_work(exc, run, self.instrument, window_periods=charge.window_periods
                   if charge.from_contacts and charge.waveforms != "start-up" else None)
        check_vibration_work(exc, run)
        if run.realisations > 1 and not exc.has_noise:
            raise SceneError(f"[run] realisations = {run.realisations} needs a random excitation "
                             "([excitation] kind = 'random', or 'harmonics' with band_hz or "
                             f"psd_file): with kind = {exc.kind!r} every realisation is the same")
        check_ensemble_work(run)
        if arr.cells > 0 and dev.cells != 1:
            raise SceneError(f"[array] cells = {arr.cells} and [device] cells = {dev.cells}: set "
                             "one of them ([device] cells: identical copies; [array] cells: cells "
                             "with their own dynamics)")
        if arr.connection != "parallel" and self.circuit.kind != "rectifier":
            raise SceneError(f"[array] connection = {arr.connection!r} needs [circuit] kind = "
                             f"'rectifier' (it is {self.circuit.kind!r})")
        check_array_work(arr, exc, run)
        check_shape_scene(self)

    # -- construction -----------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict, *, base_dir: Path | None = None, source: str = "<dict>",
                  text: str = "") -> "Scene":
        return build(data, base_dir=base_dir, source=source, text=text)

    def with_values(self, **sections: dict) -> "Scene":
        """A copy with some file-level keys changed, validated again.

        ``scene.with_values(excitation={"frequency_hz": 30.0})``

        Values may be numpy scalars or arrays (``np.float32(30)``, ``np.int64(3)``): they
        are taken as the Python numbers (lists) they hold. A section that is not a dict
        raises :class:`TypeError` naming it.
        """
        data = copy.deepcopy(self.raw)
        for sec, values in sections.items():   # a renamed key under either name
            if not isinstance(values, dict):
                raise TypeError(f"with_values({sec}={values!r:.60}): expected a dict of "
                                f"[{sec}] keys and file-level values, e.g. "
                                f"with_values({sec}={{'key': value}})")
            values = {k: _python_value(v) for k, v in values.items()}
            _one_capacitance(data, sec, values)
            update_section(data, sec, values)
        base = Path(self.source).parent if self.source not in ("<default>", "<dict>") else None
        scene = build(data, base_dir=base, source=self.source, text=self.text, warn=False,
                      settings=self.settings)
        if "field" in sections:   # explicit field settings: refuse bad ones at once
            check_field(scene)
        return scene

    # -- provenance -------------------------------------------------------
    def field_inputs(self) -> dict:
        """Every input the field solution depends on (the keys flagged ``field`` in the
        schema), as file-level values ("auto" resolved). Raises :class:`SceneError` if a
        field value is bad (the rules between the shape and other sections are
        check_field's: they do not change the field's inputs)."""
        if self.field_problems:
            raise SceneError("; ".join(self.field_problems))
        full = with_defaults(self.raw)
        out: dict[str, Any] = {"schema": FIELD_SCHEMA}
        for sec, keys in FIELD_KEYS.items():
            out[sec] = {HASH_NAMES.get((sec, k), k): full[sec][k] for k in keys}
        for sec, key in AUTO_KEYS:   # (no renamed key takes "auto")
            if out[sec][key] == "auto":
                out[sec][key] = _auto_mm(getattr(getattr(self, sec), SCHEMA[sec][key].attr))
        out["device"] = shape_field_inputs(out["device"], self.device.shape, full["device"],
                                           HASH_NAMES)
        if out["field"].get("mesh_motion") == "remesh":   # the hash of every cache before #40
            del out["field"]["mesh_motion"]
        if out["device"].get("electrodes") == "both":     # the pair's: the hash before #51
            del out["device"]["electrodes"]
        if out["field"].get("mesh_grading") == "uniform":  # the hash of every cache before #55
            del out["field"]["mesh_grading"]
        return out

    def field_hash(self) -> str:
        """SHA-256 of :meth:`field_inputs` (the surrogate cache key)."""
        blob = json.dumps(self.field_inputs(), sort_keys=True, default=float).encode()
        return hashlib.sha256(blob).hexdigest()

    def to_dict(self) -> dict:
        """File-level values of every key (defaults filled in)."""
        return with_defaults(self.raw)

    # -- derived ----------------------------------------------------------
    @property
    def field_problems(self) -> tuple[str, ...]:
        """Every bad field-only value (empty when a field stage may run)."""
        return self.field.problems if isinstance(self.field, _RefusedField) else ()

    @property
    def has_gap_lines(self) -> bool:
        """Whether this scene's field solves sample the breakdown gap lines (the resolved
        ``[field] method``'s entry: the axisymmetric one, the ball on the axis;
        :func:`tengfield.scene.shapes.gap_lines_problem` says why not)."""
        return gap_lines_problem(self.device, self.field) is None

    @property
    def is_axisymmetric(self) -> bool:
        """On-axis ball in a body of revolution: the field is 2D (r, z)."""
        return self.field.ball_offset == 0.0


def _python_value(value):
    """A numpy scalar or array as the Python number, bool, string or list it holds
    (the schema's checks take Python values); anything else unchanged."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return type(value)(_python_value(v) for v in value)
    return value


def check_field(scene: Scene) -> None:
    """Raise :class:`SceneError` naming every bad field-only value of ``scene``.

    Call it where a field stage starts (field solve, surrogate, ``tengfield
    field``/``run``/``precompute``/``sweep``): field-only values (``[field]``
    keys and the geometry ranges a mesh needs) never fail a dynamics-only run.
    """
    problems = list(scene.field_problems)
    if problems:
        raise SceneError("; ".join(problems))


def _auto_mm(value_si: float) -> float:
    """An SI length as the file-level millimetre number."""
    return float(f"{value_si * 1e3:.12g}")



def build(data: dict, *, base_dir: Path | None, source: str, text: str,
          warn: bool = True, settings: tuple = ()) -> Scene:
    """A :class:`Scene` from file-level values by section (a parsed scene file, or
    :meth:`Scene.with_values`): unknown sections and keys refused, every value checked
    and turned into SI, the files it names read (relative to ``base_dir``). A renamed
    key (:data:`RENAMED_KEYS`) is read under its old name with one warning (``warn``);
    ``scene.raw`` keeps the names as given."""
    if not isinstance(data, dict):
        raise SceneError(f"{source}: a scene is a TOML table")
    given_names = data
    data = _renamed(data, source, warn)
    for sec in data:
        if sec in PASSTHROUGH_SECTIONS:   # kept in scene.raw, validated by their own package
            if not isinstance(data[sec], dict):
                raise SceneError(f"{source}: [{sec}] must be a table")
            continue
        if sec not in SCHEMA:
            raise SceneError(f"{source}: unknown section [{sec}]" + suggest(sec, SCHEMA)
                             + f"; sections are {', '.join('[' + s + ']' for s in SCHEMA)}")
        if not isinstance(data[sec], dict):
            raise SceneError(f"{source}: [{sec}] must be a table")
        for key in data[sec]:
            if key not in SCHEMA[sec]:
                raise SceneError(f"{source}: unknown key [{sec}] {key}" + suggest(key, SCHEMA[sec]))
    if warn:   # a length in metres where mm is asked (the file's keys; --set's: with_settings)
        from .plausible import warn_metres_for_mm
        warn_metres_for_mm(data)
    components = None
    if isinstance(data.get("excitation"), dict) and data["excitation"].get("kind") == "harmonics":
        # the lists stay in scene.raw (with_values, to_dict, the written scene); the
        # build below sees the fundamental's scalar values
        data, components = harmonic_components(data)
    values: dict[str, dict[str, Any]] = {}
    problems: list[str] = []
    for sec, keys in SCHEMA.items():
        given = data.get(sec, {})
        values[sec] = {}
        for key, spec in keys.items():
            raw = given.get(key, spec.default)
            if sec != "field":
                values[sec][spec.attr] = convert(sec, key, raw, spec)
                continue
            try:   # field-only: kept for check_field, never fails a dynamics run
                values[sec][spec.attr] = convert(sec, key, raw, spec)
            except SceneError as exc:
                problems.append(str(exc))
                values[sec][spec.attr] = convert(sec, key, spec.default, spec)

    values["device"]["stroke"] = shape_of(values["device"]["shape"]).stroke(
        values["device"], data.get("device", {}))   # a shell's: cavity - ball diameter
    dev = Device(**values["device"])
    exc_vals = values["excitation"]
    record = {}
    if exc_vals["kind"] == "recorded":
        rec = read_recorded(exc_vals, base_dir)
        record = {f.name: getattr(rec, f.name) for f in dataclasses.fields(rec)}
    psd = (None, None)
    if exc_vals["kind"] in ("random", "harmonics") and exc_vals["psd_file"] and not exc_vals["band"]:
        psd = read_psd(exc_vals["psd_file"], base_dir)
    exc = Excitation(**exc_vals, **record, harmonics=components or (),
                     psd_frequencies=psd[0], psd_values=psd[1])
    fvals = values["field"]
    if fvals["domain_radius"] is None:
        fvals["domain_radius"] = auto_domain_radius(dev, fvals["ball_offset"])
    fld = Field(**fvals)
    problems += field_problems(dev, fld, explicit=set(data.get("field", {})))
    problems += shape_field_problems(dev, fld)
    lines_problem = gap_lines_problem(dev, fld, NUMERIC_SIGMA)
    stated_sigma = data["device"].get(SURFACE_CHARGE_KEY) if isinstance(data.get("device"), dict) \
        else None
    charge_model = values["charge"]["model"]
    if stated_sigma == "breakdown" and charge_model == "contact":
        raise SceneError(f'{source}: [device] {SURFACE_CHARGE_KEY} = "breakdown" and [charge] '
                         'model = "contact" contradict each other: the contacts make the '
                         "charge and [charge] discharge caps it (allowed there: "
                         + ", ".join(repr(c) for c in SCHEMA["charge"]["discharge"].check[1])
                         + f"); drop [device] {SURFACE_CHARGE_KEY}")
    humidity = values["charge"]["relative_humidity"]
    from ..charge_models import charge_model as charge_entry
    if humidity > 0.0 and not charge_entry(charge_model).reads("relative_humidity_percent"):
        raise SceneError(f"{source}: [charge] relative_humidity_percent = {humidity * 100:g} "
                         f'acts only with [charge] model = "contact" (this scene\'s is '
                         f"{charge_model!r}): the humidity law moves the contacts' sigma_eq, "
                         'tau and the cap; set model = "contact" or drop the key')
    if humidity > 0.0 and values["breakdown"]["paschen"] == "empirical":
        raise SceneError(f"{source}: [charge] relative_humidity_percent = {humidity * 100:g} "
                         'with [breakdown] paschen = "empirical": the humidity law raises '
                         "Townsend's B, and the empirical table is lab air's as measured; "
                         'use paschen = "townsend" or relative_humidity_percent = 0')
    if (stated_sigma == "breakdown" or charge_model == "breakdown") and lines_problem:
        problems.append(f'[device] {SURFACE_CHARGE_KEY} = "breakdown": {lines_problem}'
                        if stated_sigma == "breakdown" else
                        f'[charge] model = "breakdown": {lines_problem}')
    instrument = _instrument(data, values, source, warn)
    return Scene(device=dev, excitation=exc, contact=Contact(**values["contact"]),
                 initial=Initial(**values["initial"]), run=Run(**values["run"]),
                 field=_RefusedField(problems) if problems else fld,
                 circuit=Circuit(**values["circuit"]), array=Array(**values["array"]),
                 breakdown=Breakdown(**values["breakdown"]),
                 reference=Reference(**values["reference"]), instrument=instrument,
                 charge=Charge(**values["charge"]),
                 raw=copy.deepcopy(given_names),
                 source=source, text=text, settings=tuple(settings))


def warn_deprecated_capacitance(value, source: str = "", *, option: str = "",
                                stacklevel: int = 2) -> None:
    """The one warning of ``[circuit] parallel_capacitance_pF`` (its name before issue
    #39), for a file (``source``) and for an option (``option``: ``--set``, ``--vary``;
    what to write is that option then). A 0 (every key at its default: scene.to_dict(),
    report's recommended-*.toml) is not a user's value: no warning; under mpirun rank 0's
    only."""
    if value in (0, 0.0) or _launched_rank() != 0:
        return
    if option:
        source = f"{option} circuit.parallel_capacitance_pF"
    shown = value if isinstance(value, str) else show(value)   # --vary's text as written
    write = (f"{option} instrument.capacitance_pF={shown}" if option
             else f"[instrument] capacitance_pF = {show(value)}")
    warnings.warn(f"{source}: [circuit] parallel_capacitance_pF is now [instrument] "
                  f"capacitance_pF: write {write} (the old key is read until the next "
                  "release)", FutureWarning, stacklevel=stacklevel)


def _instrument(data: dict, values: dict, source: str, warn: bool) -> Instrument:
    """The ``[instrument]`` of a scene being built; its ``capacitance_pF`` becomes the
    circuit's C_p (``values["circuit"]["parallel_capacitance"]``, which every circuit
    reads). ``[circuit] parallel_capacitance_pF`` (its name before issue #39) is read with
    one warning (``warn``); both given with different values are refused."""
    circuit = data.get("circuit") if isinstance(data.get("circuit"), dict) else {}
    section = data.get("instrument") if isinstance(data.get("instrument"), dict) else None
    old_given = "parallel_capacitance_pF" in circuit
    # a file of every key at its default (scene.to_dict(), report's recommended-*.toml)
    # holds the old key at 0 (no instrument): not a user's value, no warning
    if old_given and warn:
        warn_deprecated_capacitance(circuit["parallel_capacitance_pF"], source, stacklevel=5)
    inst = dict(values["instrument"])
    if section is not None and "capacitance_pF" in section:
        if old_given and values["circuit"]["parallel_capacitance"] != inst["capacitance"]:
            raise SceneError(f"{source}: [instrument] capacitance_pF = "
                             f"{show(section['capacitance_pF'])} and [circuit] "
                             f"parallel_capacitance_pF = {show(circuit['parallel_capacitance_pF'])} "
                             "are the same capacitance: give [instrument] capacitance_pF only")
        values["circuit"]["parallel_capacitance"] = inst["capacitance"]
    else:
        inst["capacitance"] = values["circuit"]["parallel_capacitance"]
    return Instrument(**inst, given=section is not None)


def _one_capacitance(data: dict, sec: str, values: dict) -> None:
    """C_p changed by :meth:`Scene.with_values` under either name (``[circuit]
    parallel_capacitance_pF``, ``[instrument] capacitance_pF``) replaces it under both: a
    scene with an ``[instrument]`` takes a new ``[circuit]`` value as the instrument's (an
    uncertainty study or a fit varies the old name), and a new ``[instrument]`` value
    drops the old key. Changes ``values`` and ``data`` in place."""
    if sec == "circuit" and "parallel_capacitance_pF" in values and "instrument" in data:
        data["instrument"] = dict(data["instrument"])
        data["instrument"]["capacitance_pF"] = values.pop("parallel_capacitance_pF")
    elif sec == "instrument" and "capacitance_pF" in values and "circuit" in data:
        data["circuit"] = {k: v for k, v in data["circuit"].items()
                           if k != "parallel_capacitance_pF"}
