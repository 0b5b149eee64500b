"""The ``[design]`` section of a scene, validated (by this package, like ``[fit]``).

Scene syntax (every key optional except ``[design.vary]``)::

    [design]
    objective = "power_density"   # power_density [W/m^3], power [W], charge (Q_SC pp [C]),
                                  # harvested_power [W] (rectifier + store of [circuit]),
                                  # stroke (Δh [m]: with require, the largest full-contact stroke),
                                  # voltage (V_OC pp [V]), current (I_SC pp [A]);
                                  # or a list of up to four: the first drives the search, all
                                  # are reported (design.png: the Pareto plot of the first two)
    aggregate = "mean"            # over the band: "mean" or "min" (worst case), or "pNN" (e.g.
                                  # "p10"): the NN-th percentile over [uncertainty.vary] at each
                                  # band point, then the band's mean (needs [uncertainty])
    candidates = 200              # evaluation budget (distinct candidates)
    seed = 1
    require = "none"              # or "upper-contact" / "regular-contact" at every band point
    load = "one"                  # matched load: "one" resistor for the band, or "each" point's own
    load_ohm = [1e6, 1e9]         # optional: the matched load searched inside this range [ohm]
    max_field_solves = 1000       # refuse a design that may need more field solves than this
    geometry = "follow"           # tube and electrode follow a varied ball (docs/design.md), "fixed"
    field = "coarse"              # the design's field settings (degree 2, h = min(1 mm, d/5)), "scene"
    batch = 16                    # candidates per refinement round
    settle_periods = 20           # per band point: transient, then
    window_periods = 20           # the averaging window
    samples_per_period = 200
    resolution = 1e-3             # varied values snap to this fraction of their range
    [design.vary]                 # any numeric [device] key and [circuit] load_ohm: [min, max]
    stroke_mm = [1.0, 5.0]
    [design.excitation]           # the band: every frequency x every amplitude
    frequency_hz = [33.0]
    amplitude_mm = [0.5, 0.75, 1.0]
"""
from __future__ import annotations

import difflib
import math
import warnings
from dataclasses import dataclass
from dataclasses import field as _field

from ..errors import SceneError
from .._registry import lookup
from ..scene.schema import RENAMED_KEYS, SCHEMA, SURFACE_CHARGE_KEY
from ..scene.schema import convert as _convert

#: objective -> the output quantity it scores (tengfield.quantities: name, unit, label);
#: "stroke" is the device's own stroke Δh
OBJECTIVE_QUANTITIES = {
    "power_density": "load.power_density_W_per_m3",
    "power": "load.mean_power_W",
    "charge": "peak_to_peak.Q_sc_C",
    "voltage": "peak_to_peak.V_oc_V",       # the ideal V_OC = Q_SC / C_T
    "current": "peak_to_peak.I_sc_A",       # dQ_SC/dz z': the spline's derivative
    "harvested_power": "rectifier.average_harvested_power_W",
}


def _unit(objective: str) -> str:
    """The SI unit of an objective, from the quantity table."""
    from ..quantities import QUANTITIES
    return QUANTITIES[OBJECTIVE_QUANTITIES[objective].rpartition(".")[2]].unit


def objective_label(objective: str) -> str:
    """Words for an objective (axis labels, the answer): the quantity table's, without
    its unit (``"short-circuit charge Q_SC, peak-to-peak"``)."""
    if objective not in OBJECTIVE_QUANTITIES:
        return "stroke Δh"
    from ..quantities import describe
    return describe(OBJECTIVE_QUANTITIES[objective], unit=False)


#: objective -> (unit, relative-error factor on the field error bar, needs the field)
#: power ~ Q_SC^2 / C_T: dP/P <= 2 dQ/Q + dC/C <= 3 eps; charge: eps; stroke: exact
OBJECTIVES = {
    "power_density": (_unit("power_density"), 3.0, True),
    "power": (_unit("power"), 3.0, True),
    "charge": (_unit("charge"), 1.0, True),
    "voltage": (_unit("voltage"), 2.0, True),
    "current": (_unit("current"), 2.0, True),
    "harvested_power": (_unit("harvested_power"), 3.0, True),
    "stroke": ("m", 0.0, False),
}
AGGREGATES = ("mean", "min")
REQUIRES = ("none", "upper-contact", "regular-contact")
LOAD_RULES = ("one", "each")
GEOMETRY_RULES = ("follow", "fixed")
FIELD_RULES = ("coarse", "scene")
#: [design.vary] keys outside [device]: key -> section
OTHER_VARY = {"load_ohm": "circuit"}
#: varied keys searched on a logarithmic scale
LOG_KEYS = ("load_ohm",)
MAX_BAND_POINTS = 1000

KEYS = ("objective", "aggregate", "candidates", "seed", "require", "load", "geometry", "field",
        "batch", "settle_periods", "window_periods", "samples_per_period", "resolution",
        "initial_candidates", "load_ohm", "max_field_solves", "vary", "excitation")
#: the largest load a bench builds and reads (resistors, electrometer inputs ~1 GΩ): a
#: matched load past it is flagged, and [design] load_ohm = [lo, hi] keeps the search in
#: a range that can be built
BENCH_MAX_LOAD_OHM = 1e9


@dataclass
class DesignSpec:
    """``[design]`` validated; ``vary``: key -> (lo, hi) in file units; ``band``: (f [Hz], A [m])."""
    objectives: list[str] = _field(default_factory=lambda: ["power_density"])
    aggregate: str = "mean"
    candidates: int = 200
    seed: int = 1
    require: str = "none"
    load: str = "one"
    geometry: str = "follow"
    field: str = "coarse"
    batch: int = 16
    settle_periods: int = 20
    window_periods: int = 20
    samples_per_period: int = 200
    resolution: float = 1e-3
    initial_candidates: int = 0          # 0: the rule of initial_count()
    #: field solves a design may start (``[design] max_field_solves``): refused past it
    max_field_solves: int = 1000
    #: [design] load_ohm = [lo, hi] [ohm]: the matched load is searched inside it (None: free)
    load_range: tuple | None = None
    #: aggregate "pNN": NN, and the validated [uncertainty] study it is taken over
    percentile: float | None = None
    uncertainty: object = None
    vary: dict = _field(default_factory=dict)
    band: list = _field(default_factory=list)

    @property
    def objective(self) -> str:
        return self.objectives[0]

    @property
    def band_aggregate(self) -> str:
        """How band points are combined: ``aggregate``, or "mean" (of the band points'
        percentiles) for a percentile aggregate; the matched load is chosen by it."""
        return "mean" if self.percentile is not None else self.aggregate

    def initial_count(self) -> int:
        """Space-filling candidates: the given count, else the largest power of 2 <= 40 %
        of the budget (at least 4, at most the budget)."""
        if self.initial_candidates:
            return min(self.initial_candidates, self.candidates)
        n = 4
        while 2 * n <= 0.4 * self.candidates:
            n *= 2
        return min(n, self.candidates)

    def as_dict(self) -> dict:
        return {"objective": self.objectives if len(self.objectives) > 1 else self.objective,
                "aggregate": self.aggregate, "candidates": self.candidates, "seed": self.seed,
                "require": self.require, "load": self.load, "geometry": self.geometry,
                "field": self.field, "batch": self.batch, "settle_periods": self.settle_periods,
                "window_periods": self.window_periods,
                "samples_per_period": self.samples_per_period, "resolution": self.resolution,
                "initial_candidates": self.initial_count(),
                **({"load_ohm": list(self.load_range)} if self.load_range else {}),
                "vary": {k: list(v) for k, v in self.vary.items()},
                "band": [{"frequency_hz": f, "amplitude_mm": a * 1e3} for f, a in self.band],
                **({"uncertainty": robust_dict(self)} if self.percentile is not None else {})}


def robust_dict(spec: "DesignSpec") -> dict:
    """design.json's statement of a percentile aggregate: the percentile, the study's
    sample count, evaluations per band point and per candidate, its distributions."""
    u = spec.uncertainty
    return {"percentile": spec.percentile, "samples": u.samples, "method": u.method,
            "seed": u.seed, "evaluations_per_band_point": u.evaluations,
            "evaluations_per_candidate": u.evaluations * len(spec.band),
            "distributions": {d.key: d.as_dict() for d in u.inputs},
            "rule": ROBUST_RULE}


#: the rule of a percentile aggregate, stated in design.json and docs/design.md
ROBUST_RULE = ("at each band point the objective's percentile over the [uncertainty] study's "
               "evaluations of the candidate (its matched load, found at the nominal inputs, "
               "kept); the band's mean of these is the score; error bar: field/surrogate + "
               "the spread over windows + the percentile's sampling error (half-width of its "
               "distribution-free 95 % interval, combined over the band as sqrt(sum s^2) / n)")


def _suggest(word, options) -> str:
    close = difflib.get_close_matches(str(word), list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _choice(key: str, value, options) -> str:
    if not isinstance(value, str) or value not in options:
        raise SceneError(f"[design] {key} = {value!r} is not allowed: choose one of "
                         + ", ".join(map(repr, options)) + _suggest(value, options))
    return value


def _whole(key: str, value, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise SceneError(f"[design] {key} = {value!r} is out of range: allowed whole numbers "
                         f"[{lo}, {hi}]")
    return value


def _aggregate(value) -> tuple[str, float | None]:
    """(aggregate, percentile or None): "mean", "min" or "pNN" with 0 < NN < 100."""
    from ..uncertainty_study.statistics import parse_percentile

    allowed = ", ".join(map(repr, AGGREGATES)) + ' or "pNN" (0 < NN < 100, e.g. "p10")'
    try:
        p = parse_percentile(value) if isinstance(value, str) else None
    except ValueError:
        p = -1.0
    if p is not None and p > 0:
        return value, p
    if isinstance(value, str) and value in AGGREGATES:
        return value, None
    raise SceneError(f"[design] aggregate = {value!r} is not allowed: choose one of {allowed}"
                     + (_suggest(value, AGGREGATES) if p is None else ""))


#: [uncertainty.vary] keys a percentile aggregate cannot vary: the design sets them
#: (the band's excitation and run, the matched or varied load)
ROBUST_FIXED = ("excitation.frequency_hz", "excitation.amplitude_mm", "circuit.load_ohm")


def _robust_study(scene, spec: DesignSpec):
    """The validated ``[uncertainty]`` study a percentile aggregate is taken over."""
    from ..uncertainty_study.spec import uncertainty_spec

    where = f"[design] aggregate = {spec.aggregate!r}"
    raw = scene.raw.get("uncertainty")
    if not isinstance(raw, dict) or not raw.get("vary"):
        raise SceneError(f"{where} needs an [uncertainty] section with [uncertainty.vary] "
                         "(the inputs not known, docs/uncertainty.md); allowed without it: "
                         "'mean', 'min'")
    if "stroke" in spec.objectives:
        raise SceneError(f"{where} with objective 'stroke': the stroke does not vary over "
                         "[uncertainty.vary]; allowed aggregates for it: 'mean', 'min'")
    study = uncertainty_spec(scene)
    designed = set(spec.vary)   # current names (parse_design_section renamed gap_mm)
    for key in study.keys:
        section, name = key.split(".", 1)
        varied = section == "device" and name in designed or \
            name in OTHER_VARY and OTHER_VARY[name] == section and name in designed
        if varied or key in ROBUST_FIXED or section == "run":
            raise SceneError(f"[uncertainty.vary] {key!r} with {where}: the design sets this "
                             "key (a [design.vary] key, the band's excitation and run, the "
                             "load); allowed: the other numeric keys (e.g. "
                             f"device.{SURFACE_CHARGE_KEY}, contact.restitution)")
    return study


def vary_spec(key: str) -> tuple[str, tuple]:
    """(section, SCHEMA entry) of a key [design.vary] accepts, or SceneError."""
    allowed = [k for k, s in SCHEMA["device"].items() if s[1] in (float, int)
               and k not in ("tilt_deg", "tilt_azimuth_deg")] + list(OTHER_VARY)
    old_names = [old for (sec, old) in RENAMED_KEYS if sec == "device"]
    name = RENAMED_KEYS.get(("device", key), key)     # an old name (gap_mm) is still read
    if name not in allowed:
        raise SceneError(f"unknown key [design.vary] {key}" + _suggest(key, allowed + old_names)
                         + "; allowed: " + ", ".join(allowed))
    section = OTHER_VARY.get(name, "device")
    return section, SCHEMA[section][name]


#: (scene source, old key) whose [design.vary] rename this process has warned about
_WARNED_RENAMES: set = set()


def _vary(raw, scene=None) -> dict:
    """{key: (lo, hi)} under the current key names: a renamed key (``gap_mm``) is read,
    checked and reported under its written name, stored under its new one (``stroke_mm``:
    design.csv's column), with one warning line per scene."""
    from .._mpi import launched_rank
    from ..scene.shapes import design_vary_problem

    if not isinstance(raw, dict) or not raw:
        raise SceneError("[design.vary] must be a table of key = [min, max] with at least one "
                         "key, e.g. stroke_mm = [1.0, 5.0]")
    out = {}
    shape = scene.device.shape if scene is not None else "tube"
    for key, bounds in raw.items():
        section, spec = vary_spec(key)
        where = f"[design.vary] {key}"
        problem = design_vary_problem(shape, key)
        if problem:
            raise SceneError(problem)
        if (not isinstance(bounds, list) or len(bounds) != 2
                or any(isinstance(b, bool) or not isinstance(b, (int, float)) for b in bounds)):
            raise SceneError(f"{where} = {bounds!r}: expected [min, max] (two numbers)")
        for b in bounds:   # each bound must be a valid value of the key
            try:
                _convert(section, key, float(b) if spec[1] is float else b, spec)
            except SceneError as exc:
                raise SceneError(f"{where} = {bounds!r}: {exc}") from None
        lo, hi = float(bounds[0]), float(bounds[1])
        if not lo < hi:
            raise SceneError(f"{where} = {bounds!r}: min must be < max")
        if key in LOG_KEYS and lo <= 0:
            raise SceneError(f"{where} = {bounds!r}: min must be > 0 (searched on a log scale)")
        name = RENAMED_KEYS.get(("device", key), key)
        if name != key:
            if name in raw:
                raise SceneError(f"[design.vary] {key} and {name} are the same key ({key} is "
                                 f"its old name): give {name} only")
            source = getattr(scene, "source", "<scene>")
            if (source, key) not in _WARNED_RENAMES and launched_rank() == 0:
                _WARNED_RENAMES.add((source, key))
                warnings.warn(f"{source}: [design.vary] {key} is now called {name}: write "
                              f"{name} = [{lo:g}, {hi:g}] (design.csv names the column {name}; "
                              f"{key} is read until the next release)", FutureWarning,
                              stacklevel=2)
        out[name] = (lo, hi)
    return out


#: two band values closer than this (relative) are one band point: refused (design.csv's
#: columns name a point by its values' 6 significant digits, and the band mean would count
#: it twice)
BAND_DUPLICATE_RTOL = 1e-5


def _check_distinct(key: str, written: list, values: list[float]) -> None:
    """Refuse two values of ``[design.excitation] key`` within BAND_DUPLICATE_RTOL."""
    order = sorted(range(len(values)), key=values.__getitem__)
    for i, j in zip(order, order[1:]):
        a, b = values[i], values[j]
        if b - a <= BAND_DUPLICATE_RTOL * max(abs(a), abs(b)) or f"{a:g}" == f"{b:g}":
            first, second = sorted((i, j))
            raise SceneError(f"[design.excitation] {key} = {written!r}: "
                             f"{_number(values[first])} and {_number(values[second])} are one "
                             f"band point (within a relative {BAND_DUPLICATE_RTOL:g}): give "
                             "each value once")


def _number(value: float) -> str:
    """``:g`` when that is the number, else its shortest exact text (1.0000001)."""
    text = f"{value:g}"
    return text if float(text) == value else repr(value)


def _band(raw, scene) -> list[tuple[float, float]]:
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise SceneError("[design.excitation] must be a table (frequency_hz, amplitude_mm)")
    for key in raw:
        if key not in ("frequency_hz", "amplitude_mm"):
            raise SceneError(f"unknown key [design.excitation] {key}"
                             + _suggest(key, ("frequency_hz", "amplitude_mm"))
                             + "; keys are frequency_hz, amplitude_mm")
    lists = {}
    for key, default, lo_open in (("frequency_hz", scene.excitation.frequency, True),
                                  ("amplitude_mm", scene.excitation.amplitude * 1e3, False)):
        values = raw.get(key, [default])
        if not isinstance(values, list):
            values = [values]
        if not values:
            raise SceneError(f"[design.excitation] {key} = []: give at least one value")
        for v in values:
            bad = isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
            if bad or v < 0 or (lo_open and v == 0) or v > (1e5 if key == "frequency_hz" else 1e3):
                rng = "(0, 1e5]" if key == "frequency_hz" else "[0, 1000]"
                raise SceneError(f"[design.excitation] {key} = {v!r} is out of range: "
                                 f"allowed {rng}")
        lists[key] = [float(v) for v in values]
        _check_distinct(key, values, lists[key])
    band = [(f, a * 1e-3) for f in lists["frequency_hz"] for a in lists["amplitude_mm"]]
    if len(band) > MAX_BAND_POINTS:
        raise SceneError(f"[design.excitation] {len(band)} band points: allowed <= "
                         f"{MAX_BAND_POINTS}")
    return band


#: the default study of a scene without [design] (its ranges: each shape's
#: ``default_design_vary`` in scene/shapes/, fractions of the scene's values)
DEFAULT_CANDIDATES = 24


def default_design_section(scene, candidates: int | None = None) -> tuple[dict, str]:
    """([design] of the default study, the line that says so) for a scene without one:
    power density (band mean, matched load) over the stroke and the ball diameter around
    the scene's values (tube and electrode follow), at the scene's own excitation; a
    spherical shell varies its cavity and ball diameter (a ball that does not fit its
    cavity is a skipped candidate)."""
    from ..scene.shapes import shape_of

    vary = shape_of(scene.device.shape).default_design_vary(scene.device)
    section = {"objective": "power_density", "candidates": DEFAULT_CANDIDATES, "batch": 8,
               "vary": vary}
    ex = scene.excitation
    at = (f"{ex.frequency:g} Hz / {ex.amplitude * 1e3:g} mm" if periodic(ex.kind)
          else f"its {ex.kind} excitation")
    over = " and ".join(f"{k} = {v}" for k, v in vary.items())
    follows = " (tube and electrodes follow the ball)" if "stroke_mm" in vary else ""
    said = (f"{scene.source} has no [design]: a default study of power density over "
            f"{over}{follows} at {at}, {candidates or DEFAULT_CANDIDATES} "
            "candidates "
            "(docs/design.md: write a [design] section for your own)")
    return section, said


def periodic(kind: str) -> bool:
    """Does ``[excitation] kind`` have a band (a frequency and amplitude to vary)?
    Asks the kind's entry in ``EXCITATIONS`` (random and harmonics are scored as given)."""
    from ..dynamics.excitation import EXCITATIONS
    return lookup(EXCITATIONS, kind, "[excitation] kind").periodic


def recorded(kind: str) -> bool:
    """Is ``[excitation] kind`` a measured record (fixed length, no band)?"""
    from ..dynamics.excitation import EXCITATIONS
    return lookup(EXCITATIONS, kind, "[excitation] kind").recorded


def _load_range(value) -> tuple[float, float]:
    """``[design] load_ohm = [min, max]`` [ohm], 0 < min < max, finite."""
    ok = (isinstance(value, list) and len(value) == 2
          and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                  for v in value))
    if not ok:
        raise SceneError(f"[design] load_ohm = {value!r}: expected [min, max] in ohm, e.g. "
                         "[1e6, 1e9] (the range the matched load is searched in)")
    lo, hi = float(value[0]), float(value[1])
    if not 0 < lo < hi:
        raise SceneError(f"[design] load_ohm = {value!r}: expected [min, max] with "
                         "0 < min < max, e.g. [1e6, 1e9]")
    return lo, hi


def band_run(spec: DesignSpec, frequency: float) -> dict:
    """``[run]`` keys of a band point at ``frequency`` [Hz]: settle + window periods, sampled
    ``samples_per_period`` times a period (the run a candidate is scored on)."""
    periods = spec.settle_periods + spec.window_periods
    return {"duration_s": periods / frequency, "settle_periods": spec.settle_periods,
            "sample_rate_hz": spec.samples_per_period * frequency}


def _check_band_runs(scene, spec: DesignSpec) -> None:
    """Every band point's run (settle + window periods, samples_per_period a period) as
    the scene's [run] checks would take it, before any work: a run past a limit is one
    line naming the [design] keys that set it (every candidate would be skipped)."""
    kind = scene.excitation.kind
    for f, a in spec.band:
        run = band_run(spec, f)
        try:
            if periodic(scene.excitation.kind):
                scene.with_values(excitation={"frequency_hz": f}, run=run)
            else:
                scene.with_values(run=run)
        except SceneError as exc:
            raise SceneError(
                f"[design] settle_periods = {spec.settle_periods}, window_periods = "
                f"{spec.window_periods}, samples_per_period = {spec.samples_per_period}: the "
                f"run of band point {f:g} Hz" + (f" / {a * 1e3:g} mm" if periodic(kind) else
                                                  f" ({kind})") + " "
                f"({run['duration_s']:.4g} s at {run['sample_rate_hz']:.4g} Hz) is refused: "
                f"{exc}") from None


def parse_design_section(scene, overrides: dict | None = None) -> DesignSpec:
    """Validate ``scene.raw["design"]`` (with ``overrides`` of top-level keys) -> :class:`DesignSpec`."""
    raw = dict(scene.raw.get("design", {}) or {})
    raw.update(overrides or {})
    for key in raw:
        if key not in KEYS:
            raise SceneError(f"unknown key [design] {key}" + _suggest(key, KEYS)
                             + f"; keys are {', '.join(KEYS)}")
    if recorded(scene.excitation.kind):
        raise SceneError("[excitation] kind = 'recorded': tengfield design scores sine "
                         "([design.excitation] band), random or harmonics excitations; a "
                         "record has a fixed length and no band")
    if not periodic(scene.excitation.kind) and "excitation" in raw:
        raise SceneError(f"[design.excitation] needs [excitation] kind = 'sine': a "
                         f"{scene.excitation.kind!r} excitation is scored as the scene gives it "
                         "(leave [design.excitation] out)")
    if scene.array.cells:
        raise SceneError(f"[array] cells = {scene.array.cells}: tengfield design scores one "
                         "device ([device] cells identical cells); allowed 0")
    spec = DesignSpec()
    objective = raw.get("objective", "power_density")
    objectives = objective if isinstance(objective, list) else [objective]
    if not 1 <= len(objectives) <= 4 or len(set(map(str, objectives))) != len(objectives):
        raise SceneError(f"[design] objective = {objective!r}: give one objective or a list "
                         "of up to four different ones")
    spec.objectives = [_choice("objective", o, tuple(OBJECTIVES)) for o in objectives]
    spec.aggregate, spec.percentile = _aggregate(raw.get("aggregate", spec.aggregate))
    spec.require = _choice("require", raw.get("require", spec.require), REQUIRES)
    spec.load = _choice("load", raw.get("load", spec.load), LOAD_RULES)
    spec.geometry = _choice("geometry", raw.get("geometry", spec.geometry), GEOMETRY_RULES)
    spec.field = _choice("field", raw.get("field", spec.field), FIELD_RULES)
    spec.candidates = _whole("candidates", raw.get("candidates", spec.candidates), 4, 100000)
    spec.seed = _whole("seed", raw.get("seed", spec.seed), 0, 2**32 - 1)
    spec.batch = _whole("batch", raw.get("batch", spec.batch), 1, 4096)
    spec.settle_periods = _whole("settle_periods", raw.get("settle_periods", spec.settle_periods),
                                 0, 100000)
    spec.window_periods = _whole("window_periods", raw.get("window_periods", spec.window_periods),
                                 2, 100000)
    spec.samples_per_period = _whole("samples_per_period",
                                     raw.get("samples_per_period", spec.samples_per_period),
                                     20, 100000)
    spec.initial_candidates = _whole("initial_candidates", raw.get("initial_candidates", 0),
                                     0, 100000)
    spec.max_field_solves = _whole("max_field_solves",
                                   raw.get("max_field_solves", spec.max_field_solves), 1, 10**7)
    res = raw.get("resolution", spec.resolution)
    if isinstance(res, bool) or not isinstance(res, (int, float)) or not 0 <= res <= 0.1:
        raise SceneError(f"[design] resolution = {res!r} is out of range: allowed [0, 0.1] "
                         "(a fraction of each varied range; 0: no snapping)")
    spec.resolution = float(res)
    if "vary" not in raw:
        raise SceneError("[design.vary] is missing: give the keys to vary, e.g. "
                         "stroke_mm = [1.0, 5.0]")
    spec.vary = _vary(raw["vary"], scene)
    spec.band = _band(raw.get("excitation"), scene)
    if spec.percentile is not None:
        spec.uncertainty = _robust_study(scene, spec)
    if "load_ohm" in raw:
        spec.load_range = _load_range(raw["load_ohm"])
        if "load_ohm" in spec.vary:
            raise SceneError("[design] load_ohm and [design.vary] load_ohm: the load is either "
                             "matched within [design] load_ohm or varied, not both; give one")
    _check_band_runs(scene, spec)
    if "load_ohm" in spec.vary and spec.load == "each":
        raise SceneError("[design] load = 'each' and [design.vary] load_ohm: the load is either "
                         "varied or matched, not both; allowed load = 'one' here")
    return spec


def design_cost(scene, spec: DesignSpec):
    """What the design ``spec`` of ``scene`` will do at most, counted before any of it
    (issue #43.6; :class:`tengfield.uncertainty_study.cost.WorkCost`): ``candidates`` x band
    points evaluations (x the ``[uncertainty]`` draws for a percentile aggregate), one
    field solve per candidate when a geometry key is varied (else one; none for an
    uncharged ball), a dynamics run per evaluation."""
    from ..uncertainty_study.cost import EVALUATION_BYTES, SURROGATE_BYTES, WorkCost
    from ..uncertainty_study.evaluation import is_field_key

    band = max(len(spec.band), 1)
    draws = 1
    if spec.uncertainty is not None:
        from ..uncertainty_study.sampling import study_values
        draws = len(study_values(spec.uncertainty))
    evaluations = spec.candidates * band * draws
    keys = [f"{OTHER_VARY.get(key, 'device')}.{key}" for key in spec.vary]
    geometry = any(is_field_key(key, scene.device.shape) for key in keys)
    charged = scene.device.ball_charge != 0.0 or SURFACE_CHARGE_KEY in spec.vary
    solves = 0 if not charged else (spec.candidates if geometry else 1)
    if spec.uncertainty is not None and charged:
        solves *= max(1, draws if any(is_field_key(k, scene.device.shape)
                                      for k in spec.uncertainty.keys) else 1)
    return WorkCost(evaluations=evaluations, field_solves=solves,
                    dynamics_runs=evaluations, cache_bytes=solves * SURROGATE_BYTES,
                    memory_bytes=evaluations * EVALUATION_BYTES)
