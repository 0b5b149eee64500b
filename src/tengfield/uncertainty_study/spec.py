"""The ``[uncertainty]`` section: sample count, method, seed and ``[uncertainty.vary]``.

``[uncertainty.vary]`` maps a scene key written ``"section.key"`` (a float key of the
scene schema, in the file's units) to a distribution:

* ``{ distribution = "uniform", low = .., high = .. }``
* ``{ distribution = "normal", mean = .., std = .. }``
* ``{ distribution = "lognormal", median = .., factor = .. }`` (``factor``: the
  geometric standard deviation, > 1; ln x is normal with mean ln(median), std ln(factor))
* ``{ distribution = "triangular", low = .., mode = .., high = .. }``
* ``"device.σ" = { distribution = "breakdown-band" }`` (σ only,
  issue #38): σ log-uniform between the edges of the breakdown band of each geometry
  (:mod:`tengfield.air_breakdown.band`); the study's column holds the draw's place in the
  band, u in (0, 1): σ = −lower·(upper/lower)^u

:func:`uncertainty_spec` validates it the way every scene key is validated (one-line
:class:`~tengfield.errors.SceneError` naming key, value and allowed range): unknown keys
with a did-you-mean, a distribution whose range leaves the key's own allowed range
(normal and lognormal: their 1e-6 and 1 - 1e-6 quantiles), a sample count too small for
the number of inputs. ``tengfield scene`` calls it too.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

from .._mpi import launched_rank
from ..errors import SceneError
from ..scene.schema import (HARMONIC_KEYS, RENAMED_KEYS, SCHEMA, SURFACE_CHARGE_KEY,
                            SURFACE_CHARGE_SETTING, fmt_range, show,
                            stated_surface_charge, suggest)

SECTION = "uncertainty"
METHODS = ("sobol", "monte-carlo")
#: parameters of each distribution, in the order they are written
DISTRIBUTIONS = {"uniform": ("low", "high"), "normal": ("mean", "std"),
                 "lognormal": ("median", "factor"), "triangular": ("low", "mode", "high"),
                 "breakdown-band": ()}
#: the distribution drawn from each geometry's breakdown band (σ only: SURFACE_CHARGE_SETTING)
BAND = "breakdown-band"
KEYS = ("samples", "method", "seed", "vary", "max_field_solves")
DEFAULTS = {"samples": 256, "method": "sobol", "seed": 0, "max_field_solves": 1000}
#: the tail probability whose quantiles must lie inside the key's allowed range
#: (normal, lognormal): no scrambled Sobol point of a study under ~1e6 evaluations
#: comes nearer to 0 or 1
TAIL = 1e-6
#: Sobol (Saltelli) base samples: a power of two (the Sobol sequence's balance), at
#: least MIN_SOBOL_SAMPLES and SOBOL_SAMPLES_PER_INPUT x the inputs; Monte Carlo at
#: least MIN_MC_SAMPLES (a 5-95 % interval from fewer points is two of them)
MIN_SOBOL_SAMPLES = 16
SOBOL_SAMPLES_PER_INPUT = 4
MIN_MC_SAMPLES = 20
#: evaluations of one study (each runs the electrical stage, ~10 ms, and perhaps the
#: dynamics): 1e6 is hours on one core
MAX_EVALUATIONS = 1_000_000
#: sections whose keys are no input of a run: varying them changes no output
NOT_INPUTS = {"reference": "holds measured values to compare the run with, not inputs of "
                           "the run (varying it changes no output)"}
#: (scene source, written key) whose rename this process has warned about
_WARNED_RENAMES: set = set()
#: the standard normal quantile of 1 - TAIL (4.753...)
_TAIL_Z = 4.753424308817087
#: logarithms of the largest and smallest positive normal doubles
_LOG_MAX = math.log(1.7976931348623157e308)
_LOG_MIN = math.log(2.2250738585072014e-308)


@dataclass(frozen=True)
class Distribution:
    """One input: the scene key ``section.key`` and its distribution (file units)."""
    key: str
    kind: str
    params: dict

    @property
    def section(self) -> str:
        return self.key.split(".", 1)[0]

    @property
    def name(self) -> str:
        return self.key.split(".", 1)[1]

    def ppf(self, u):
        """Values at probabilities ``u`` (array in (0, 1)): the inverse CDF."""
        import numpy as np
        from scipy import stats

        u = np.asarray(u, dtype=float)
        p = self.params
        if self.kind == "uniform":
            return p["low"] + u * (p["high"] - p["low"])
        if self.kind == "normal":
            return stats.norm.ppf(u, loc=p["mean"], scale=p["std"])
        if self.kind == "lognormal":
            return p["median"] * np.exp(math.log(p["factor"]) * stats.norm.ppf(u))
        if self.kind == BAND:        # the place in the band; σ per geometry (band_sigma)
            return u
        width = p["high"] - p["low"]
        return stats.triang.ppf(u, (p["mode"] - p["low"]) / width, loc=p["low"], scale=width)

    def support(self) -> tuple[float, float]:
        """The values the study can draw: the ends (uniform, triangular) or the TAIL
        quantiles (normal, lognormal)."""
        if self.kind in ("uniform", "triangular"):
            return self.params["low"], self.params["high"]
        if self.kind == BAND:
            return 0.0, 1.0
        lo, hi = self.ppf([TAIL, 1.0 - TAIL])
        return float(lo), float(hi)

    def as_dict(self) -> dict:
        return {"distribution": self.kind, **self.params}


@dataclass(frozen=True)
class UncertaintySpec:
    """A validated ``[uncertainty]`` section."""
    samples: int
    method: str
    seed: int
    inputs: tuple[Distribution, ...] = field(default_factory=tuple)
    #: field solves a study may start (``[uncertainty] max_field_solves``; each takes
    #: seconds to minutes and adds a surrogate to the cache): checked before the work
    max_field_solves: int = DEFAULTS["max_field_solves"]

    @property
    def keys(self) -> list[str]:
        return [d.key for d in self.inputs]

    @property
    def evaluations(self) -> int:
        """Evaluations of the study: N (D + 2) for Saltelli's scheme (first-order and
        total indices), N for Monte Carlo."""
        d = len(self.inputs)
        return self.samples * (d + 2) if self.method == "sobol" else self.samples

    def as_dict(self) -> dict:
        return {"samples": self.samples, "method": self.method, "seed": self.seed,
                "vary": {d.key: d.as_dict() for d in self.inputs}}


def sections_of(values: dict) -> dict[str, dict]:
    """``{"contact.restitution": 0.3}`` -> ``{"contact": {"restitution": 0.3}}`` (the
    keyword arguments of :meth:`tengfield.scene.Scene.with_values`)."""
    out: dict[str, dict] = {}
    for key, value in values.items():
        sec, name = key.split(".", 1)
        out.setdefault(sec, {})[name] = float(value)
    return out


def _number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(f"{where} = {show(value)}: expected a finite number")
    return float(value)


def _distribution(key: str, given) -> Distribution:
    where = f"[uncertainty.vary] {key!r}"
    if not isinstance(given, dict):
        raise SceneError(f"{where} = {show(given)}: expected a table, e.g. "
                         '{ distribution = "uniform", low = 0.1, high = 0.5 }')
    kind = given.get("distribution")
    if "distribution" not in given:   # a --set of one parameter on an entry the scene lacks
        choices = ", ".join(repr(k) for k in DISTRIBUTIONS)
        have = ", ".join(f"{k} = {show(v)}" for k, v in given.items())
        raise SceneError(f"{where}: no distribution given (only {have}; a --set changes "
                         "an entry the scene has, it makes none): give distribution, one of "
                         f"{choices}, and its parameters, e.g. --set 'uncertainty.vary."
                         f"\"{key}\"={{distribution = \"uniform\", low = ..., high = ...}}'")
    if kind not in DISTRIBUTIONS:
        choices = ", ".join(repr(k) for k in DISTRIBUTIONS)
        raise SceneError(f"{where}: distribution = {show(kind)} is not allowed: choose one of "
                         f"{choices}" + (suggest(kind, DISTRIBUTIONS) if isinstance(kind, str) else ""))
    if kind == BAND and key != SURFACE_CHARGE_SETTING:
        raise SceneError(f"{where}: distribution = {show(kind)} is for "
                         f"{SURFACE_CHARGE_SETTING!r} only "
                         "(the breakdown band of each geometry)")
    names = DISTRIBUTIONS[kind]
    for name in given:
        if name != "distribution" and name not in names:
            takes = f"it takes {', '.join(names)}" if names else (
                "it takes no parameters (each geometry's band gives the range)")
            raise SceneError(f"{where}: unknown parameter {name!r} of a {kind} distribution"
                             + suggest(name, names) + f"; {takes}")
    missing = [n for n in names if n not in given]
    if missing:
        raise SceneError(f"{where}: a {kind} distribution needs {', '.join(names)} "
                         f"(missing {', '.join(missing)})")
    p = {n: _number(f"{where} {n}", given[n]) for n in names}
    if kind in ("uniform", "triangular") and not p["low"] < p["high"]:
        raise SceneError(f"{where}: low = {p['low']:g} must be below high = {p['high']:g}")
    if kind == "triangular" and not p["low"] <= p["mode"] <= p["high"]:
        raise SceneError(f"{where}: mode = {p['mode']:g} is out of range: allowed "
                         f"[{p['low']:g}, {p['high']:g}] (low, high)")
    if kind == "normal" and not p["std"] > 0.0:
        raise SceneError(f"{where}: std = {p['std']:g} is out of range: allowed (0, inf)")
    if kind == "lognormal":
        if not p["median"] > 0.0:
            raise SceneError(f"{where}: median = {p['median']:g} is out of range: allowed (0, "
                             "inf) (a lognormal value is positive; for a negative key use "
                             "normal or uniform)")
        if not p["factor"] > 1.0:
            raise SceneError(f"{where}: factor = {p['factor']:g} is out of range: allowed (1, "
                             "inf) (the geometric standard deviation)")
        # its TAIL quantiles median x factor^(+-z) must be finite doubles: checked in
        # logarithms, before numpy overflows (issue #43.16: factor = 1e300)
        z = _TAIL_Z
        top = math.log(p["median"]) + z * math.log(p["factor"])
        low = math.log(p["median"]) - z * math.log(p["factor"])
        if top >= _LOG_MAX or low <= _LOG_MIN:
            limit = math.exp(min(_LOG_MAX - math.log(p["median"]),
                                 math.log(p["median"]) - _LOG_MIN) / z)
            raise SceneError(f"{where}: factor = {p['factor']:g} is out of range: its {TAIL:g} "
                             f"quantiles median x factor^(+-{z:.3g}) leave the doubles; allowed "
                             f"(1, {limit:.6g}) with median = {p['median']:g}")
    return Distribution(key, kind, p)


def _check_key(key: str, scene=None) -> str:
    """``key`` is ``"section.key"`` of a float key of the schema that is an input of a
    run; returns it under its current name (``device.gap_mm`` -> ``device.stroke_mm``,
    with the warning the scene's own ``gap_mm`` gets)."""
    where = f"[uncertainty.vary] {key!r}"
    if not isinstance(key, str) or "." not in key:
        raise SceneError(f"{where}: write the scene key as \"section.key\", e.g. "
                         "\"contact.restitution\"")
    sec, name = key.split(".", 1)
    new = RENAMED_KEYS.get((sec, name))
    if new is not None:
        source = getattr(scene, "source", "<scene>")
        if (source, key) not in _WARNED_RENAMES and launched_rank() == 0:
            _WARNED_RENAMES.add((source, key))
            warnings.warn(f"{source}: [uncertainty.vary] {key!r} is now called "
                          f"'{sec}.{new}': write \"{sec}.{new}\" ({name} is read until the "
                          "next release)", FutureWarning, stacklevel=3)
        name = new
    if sec in NOT_INPUTS:
        raise SceneError(f"{where}: [{sec}] {NOT_INPUTS[sec]}; vary an input of the run "
                         "([device], [excitation], [contact], [initial], [circuit], ...)")
    if sec not in SCHEMA:
        raise SceneError(f"{where}: unknown section [{sec}]" + suggest(sec, SCHEMA)
                         + f"; sections are {', '.join(SCHEMA)}")
    if name not in SCHEMA[sec]:
        full = [f"{sec}.{k}" for k in SCHEMA[sec]]
        raise SceneError(f"{where}: unknown key [{sec}] {name}" + suggest(key, full))
    spec = SCHEMA[sec][name]
    if spec.type is not float:
        kind = {str: "a text key", int: "a whole-number key", tuple: "a list key"}[spec.type]
        raise SceneError(f"{where}: [{sec}] {name} is {kind}; only numeric (real-valued) keys "
                         "can be varied")
    from ..charge_models import charge_model_of, models_reading
    if sec == "charge" and scene is not None and not charge_model_of(scene).reads(name):
        raise SceneError(f"{where}: [charge] {name} acts only with [charge] model = "
                         f"{models_reading(name)} (tengfield.charge_models); this scene's is "
                         f"{scene.charge.model!r}: set [charge] model = {models_reading(name)} "
                         f"or vary {SURFACE_CHARGE_SETTING!r}")
    # kept: 'harmonics' is the one kind whose HARMONIC_KEYS are lists (the schema's own rule)
    if (sec == "excitation" and name in HARMONIC_KEYS and scene is not None
            and scene.excitation.kind == "harmonics"):
        raise SceneError(f"{where}: with [excitation] kind = 'harmonics' {name} is a list (one "
                         "entry per component); a list key cannot be varied (allowed with kind "
                         "'sine', 'random' or 'recorded')")
    return f"{sec}.{name}"


def _check_support(dist: Distribution) -> None:
    """The values the distribution can draw lie inside the key's own allowed range."""
    spec = SCHEMA[dist.section][dist.name]
    constraint = spec.check
    if not constraint or constraint[0] != "range" or dist.kind == BAND:
        return
    lo, hi = dist.support()
    _, a, b, a_open, b_open = constraint[:5]
    below = lo < a or (a_open and lo == a)
    above = hi > b or (b_open and hi == b)
    if below or above:
        what = ("its values" if dist.kind in ("uniform", "triangular")
                else f"its {TAIL:g} and {1 - TAIL:.6g} quantiles")
        raise SceneError(f"[uncertainty.vary] {dist.key!r}: a {dist.kind} distribution "
                         f"{dist.as_dict()} reaches {lo:.6g} .. {hi:.6g} ({what}): [{dist.section}] "
                         f"{dist.name} is allowed {fmt_range(constraint)}")


def uncertainty_spec(scene, required: bool = True) -> UncertaintySpec | None:
    """The scene's ``[uncertainty]`` section, validated (:class:`SceneError` on a bad
    one). None when the scene has none and ``required`` is False; ``tengfield scene``
    calls ``uncertainty_spec(scene, required=False)``."""
    raw = scene.raw.get(SECTION)
    if raw is None:
        if not required:
            return None
        raise SceneError(f"{scene.source}: no [uncertainty] section: add one with "
                         "[uncertainty.vary], e.g. \"contact.restitution\" = { distribution = "
                         "\"uniform\", low = 0.05, high = 0.5 } (docs/uncertainty.md)")
    if not isinstance(raw, dict):
        raise SceneError(f"{scene.source}: [uncertainty] must be a table")
    if scene.array.cells > 0:
        raise SceneError(f"[array] cells = {scene.array.cells}: a study evaluates one cell's "
                         "electrical stage per sample; an array's cells are not supported by "
                         "[uncertainty] (allowed [array] cells = 0; use [device] cells)")
    from ..dynamics.models import model_of
    if model_of(scene).lateral:
        raise SceneError("[contact] model = '3d': a study evaluates the on-axis surrogate; the "
                         "3D model's off-axis field is not supported by [uncertainty] (allowed "
                         "'impact', 'soft')")
    for key in raw:
        if key not in KEYS:
            raise SceneError(f"unknown key [uncertainty] {key}" + suggest(key, KEYS)
                             + f"; keys are {', '.join(KEYS)}")
    method = raw.get("method", DEFAULTS["method"])
    if method not in METHODS:
        raise SceneError(f"[uncertainty] method = {show(method)} is not allowed: choose one of "
                         + ", ".join(repr(m) for m in METHODS)
                         + (suggest(method, METHODS) if isinstance(method, str) else ""))
    seed = raw.get("seed", DEFAULTS["seed"])
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= 2**32 - 1:
        raise SceneError(f"[uncertainty] seed = {show(seed)}: allowed a whole number in "
                         f"[0, {2**32 - 1}]")
    vary = raw.get("vary")
    if not isinstance(vary, dict) or not vary:
        raise SceneError("[uncertainty.vary] is missing or empty: give at least one input, e.g. "
                         "\"contact.restitution\" = { distribution = \"uniform\", low = 0.05, "
                         "high = 0.5 }")
    inputs, named = [], {}
    for written, given in vary.items():
        key = _check_key(written, scene)
        if key in named:
            raise SceneError(f"[uncertainty.vary] {named[key]!r} and {written!r} are the same "
                             f"key ({key}): give {key!r} only")
        named[key] = written
        dist = _distribution(key, given)
        _check_support(dist)
        inputs.append(dist)
    samples = raw.get("samples", DEFAULTS["samples"])
    if isinstance(samples, bool) or not isinstance(samples, int):
        raise SceneError(f"[uncertainty] samples = {show(samples)}: expected a whole number")
    d = len(inputs)
    if method == "sobol":
        least = max(MIN_SOBOL_SAMPLES, SOBOL_SAMPLES_PER_INPUT * d)
        if samples < least or samples & (samples - 1):
            power = 1 << max(least - 1, 1).bit_length()
            raise SceneError(f"[uncertainty] samples = {samples} is too small or not a power of "
                             f"two for method = \"sobol\" with {d} input{'s' * (d > 1)}: allowed "
                             f"a power of two >= {least} (max({MIN_SOBOL_SAMPLES}, "
                             f"{SOBOL_SAMPLES_PER_INPUT} x inputs)), e.g. {power}")
    elif samples < max(MIN_MC_SAMPLES, d + 1):
        raise SceneError(f"[uncertainty] samples = {samples} is too small for method = "
                         f"\"monte-carlo\" with {d} input{'s' * (d > 1)}: allowed >= "
                         f"{max(MIN_MC_SAMPLES, d + 1)}")
    limit = raw.get("max_field_solves", DEFAULTS["max_field_solves"])
    if isinstance(limit, bool) or not isinstance(limit, int) or not 0 <= limit <= 10**9:
        raise SceneError(f"[uncertainty] max_field_solves = {show(limit)}: allowed a whole "
                         "number in [0, 1000000000] (the field solves a study may start)")
    spec = UncertaintySpec(samples=samples, method=method, seed=seed, inputs=tuple(inputs),
                           max_field_solves=limit)
    if spec.evaluations > MAX_EVALUATIONS:
        raise SceneError(f"[uncertainty] samples = {samples} gives {spec.evaluations} "
                         f"evaluations: allowed <= {MAX_EVALUATIONS:.0e}")
    _check_scenes(scene, spec)
    return spec


def draws_from_band(scene) -> bool:
    """Whether the scene's ``[uncertainty.vary]`` draws σ from the breakdown band."""
    vary = (scene.raw.get(SECTION) or {}).get("vary") if isinstance(scene.raw, dict) else None
    given = vary.get(SURFACE_CHARGE_SETTING) if isinstance(vary, dict) else None
    return isinstance(given, dict) and given.get("distribution") == BAND


#: a breakdown-band draw as messages name it
BAND_DRAW = f'[uncertainty.vary] "{SURFACE_CHARGE_SETTING}" = {{ distribution = "{BAND}" }}'


def check_study_combination(scene) -> None:
    """Refuse in one line, before the first solve, a study whose charge needs the
    breakdown gap lines its field solver does not give (breakdown-band draws, or σ =
    "breakdown"): :func:`tengfield.air_breakdown.check_gap_lines`, the check ``run``
    makes (``design`` asks it too)."""
    from ..air_breakdown import check_gap_lines, uses_breakdown_charge
    from ..scene.shapes import NUMERIC_SIGMA
    if draws_from_band(scene):
        check_gap_lines(scene, BAND_DRAW, "draw sigma from another distribution")
    elif uses_breakdown_charge(scene):
        check_gap_lines(scene, f'[device] {SURFACE_CHARGE_KEY} = "breakdown"', NUMERIC_SIGMA)


def band_sigma(band, place: float) -> float:
    """σ [µC/m², negative: PTFE] at ``place`` u in [0, 1] of ``band`` (a
    :class:`tengfield.air_breakdown.Band`): log-uniform, −lower·(upper/lower)^u."""
    return -1e6 * band.lower * (band.upper / band.lower) ** float(place)


#: inputs up to which every corner of the joint box is built (2^D scenes); beyond, the
#: corners of every pair of inputs (rules between keys are between two keys)
MAX_CORNER_INPUTS = 8


def _check_scenes(scene, spec: UncertaintySpec) -> None:
    """The draws' box builds valid scenes at its corners: each input at either end of
    what it can draw (the others nominal), every pair of inputs at their four joint
    corners, and (up to :data:`MAX_CORNER_INPUTS` inputs) every corner of the joint
    box, so a rule between keys (a ball wider than the bore, a falling threshold above
    the rising one) is named before any work (issue #43.11). σ drawn from the breakdown
    band is left out: it comes from each geometry's band."""
    import itertools

    inputs = [dist for dist in spec.inputs if dist.kind != BAND]
    ends = [dist.support() for dist in inputs]

    def check(indices, corner):
        values = {inputs[j].key: v for j, v in zip(indices, corner)}
        try:
            scene.with_values(**sections_of(values))
        except SceneError as exc:
            if len(indices) == 1:
                dist = inputs[indices[0]]
                raise SceneError(f"[uncertainty.vary] {dist.key!r} = {corner[0]:.6g} (an end of "
                                 f"its {dist.kind} distribution): {exc}") from None
            named = " with ".join(f"{k!r} = {v:.6g}" for k, v in values.items())
            raise SceneError(f"[uncertainty.vary] {named} (a corner of their joint draws, "
                             f"which the study reaches): {exc}") from None

    d = len(inputs)
    for size in (1, 2, d) if d > 2 and d <= MAX_CORNER_INPUTS else (1, 2):
        for indices in itertools.combinations(range(d), size):
            for corner in itertools.product(*(ends[j] for j in indices)):
                check(indices, corner)


#: the default study's restitution range: 0.1 fits the paper's thresholds, PTFE on
#: copper is often quoted at 0.5-0.8 (docs/uncertainty.md)
DEFAULT_RESTITUTION = (0.05, 0.8)
#: the default study's charge range, as fractions of the scene's sigma
DEFAULT_SIGMA_FACTORS = (0.5, 1.5)
DEFAULT_SAMPLES = 64


def default_uncertainty_section(scene) -> tuple[dict, str]:
    """([uncertainty] of the default study, the line that says so) for a scene without
    one: the restitution over :data:`DEFAULT_RESTITUTION` and, for a numeric non-zero
    σ, σ over :data:`DEFAULT_SIGMA_FACTORS` of the scene's, uniform; Sobol indices
    with N = :data:`DEFAULT_SAMPLES`."""
    vary = {"contact.restitution": {"distribution": "uniform", "low": DEFAULT_RESTITUTION[0],
                                    "high": DEFAULT_RESTITUTION[1]}}
    stated = stated_surface_charge(scene)
    sigma = scene.device.surface_charge * 1e6 if stated is None else stated
    if isinstance(sigma, (int, float)) and not isinstance(sigma, bool) and sigma != 0.0:
        low, high = sorted(float(f"{sigma * f:.6g}") for f in DEFAULT_SIGMA_FACTORS)
        vary = {SURFACE_CHARGE_SETTING: {"distribution": "uniform", "low": low,
                                         "high": high}, **vary}
    section = {"samples": DEFAULT_SAMPLES, "method": "sobol", "seed": 1, "vary": vary}
    said = (f"{scene.source} has no [uncertainty]: a default study of "
            + " and ".join(f"{k} uniform in [{v['low']:g}, {v['high']:g}]"
                           for k, v in vary.items())
            + f", Sobol indices, N = {DEFAULT_SAMPLES} (docs/uncertainty.md: write an "
            "[uncertainty] section for your own)")
    return section, said
