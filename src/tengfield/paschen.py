"""Paschen's law for air: the breakdown voltage of a gap (pure numpy, SI).

Townsend regime (self-sustained avalanche with secondary emission γ):

    V_b(p·d) = B·p·d / (ln(A·p·d) − ln(ln(1 + 1/γ)))

with the Townsend constants of air A = 15 cm⁻¹ Torr⁻¹ = 11.25 (Pa·m)⁻¹,
B = 365 V cm⁻¹ Torr⁻¹ = 273.75 V/(Pa·m) (Raizer, *Gas Discharge Physics*,
Springer 1991, Table 4.1, fitted for E/p = 100–800 V cm⁻¹ Torr⁻¹) and
γ = 0.01 (a typical value for metal cathodes in air, Raizer §4.5). At 1 atm
this gives V_min = B·e·ln(1 + 1/γ)/A ≈ 305 V at d ≈ 11 µm, 865 V at 0.1 mm,
5.03 kV at 1 mm.

Where that formula holds and what is used outside (one curve, continuous and
non-decreasing in d, so a shorter line never breaks down at a higher voltage):

=====================================  ===================================================
p·d                                    V_b
=====================================  ===================================================
d ≤ d_fe = V_min / E_fe                field emission: constant field E_fe = 350 V/µm
                                       (Peschot et al., Micromachines 2014/Appl. Phys.
                                       Lett. 2014: ~350 V/µm measured below ~1 µm)
d_fe < d, p·d < (p·d)_min              plateau V_min (the left branch of Paschen's curve
                                       does not happen in air at µm gaps: the discharge
                                       finds a longer path or field emission takes over)
p·L < (p·d)_min (low pressure)         long path: the discharge takes the longest path
                                       L the device offers (``longest_path``), so
                                       V_b = V_Townsend(p·L) on the left branch, capped by
                                       E_fe·d; no Townsend breakdown at all ("vacuum",
                                       A·p·L ≤ ln(1 + 1/γ)) leaves E_fe·d, the µm-gap
                                       value: vacuum breakdown of mm gaps is lower and is
                                       not modelled (air no longer limits the charge)
(p·d)_min ≤ p·d ≤ (p·d)_s              Townsend formula above (its valid range)
p·d > (p·d)_s = 266.6 Pa·m             streamer regime (200 Torr·cm, Raizer §12; 2.6 mm
(200 Torr·cm)                          at 1 atm): the uniform-field empirical law of air
                                       V = 24.36·x + 6.72·√x kV, x = p·d in bar·cm
                                       (Dakin et al., Electra 32, 1974), scaled to meet
                                       the Townsend value at (p·d)_s
=====================================  ===================================================

Every function takes ``d`` [m] (array or scalar) and the pressure [Pa].
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Townsend constants of air (Raizer 1991, Table 4.1): A [1/(Pa m)], B [V/(Pa m)]
AIR_A = 11.25
AIR_B = 273.75
#: secondary-emission coefficient (Raizer 1991, §4.5)
AIR_GAMMA = 0.01
#: standard atmosphere [Pa]
ATMOSPHERE = 101325.0
#: field-emission breakdown field at sub-µm gaps [V/m] (Peschot et al. 2014)
FIELD_EMISSION_FIELD = 350e6
#: upper end of the Townsend regime, p·d [Pa m] (200 Torr cm, Raizer §12)
STREAMER_PD = 200.0 * 133.322 * 1e-2
#: Dakin et al. (1974) uniform-field law of air, V [kV] = a x + b sqrt(x), x in bar cm
DAKIN = (24.36, 6.72)

REGIMES = ("field-emission", "plateau", "long-path", "vacuum", "townsend", "streamer",
           "empirical")
#: the curves ``[breakdown] paschen`` can name
CURVES = ("townsend", "empirical")
#: the default range of γ over which the band's edges are taken ([breakdown] gamma_range)
GAMMA_RANGE = (1e-4, 0.1)


def _dakin_kv(x):
    """Dakin et al. (1974), uniform-field breakdown of air at 20 C: V [kV] of x = p d [bar cm]."""
    a, b = DAKIN
    return a * x + b * math.sqrt(x)


#: Empirical uniform-field breakdown of air at 20 C (``[breakdown] paschen = "empirical"``):
#: (p·d [Pa m], V_b [V]). The first row is the measured minimum of air, 327 V at
#: 0.567 Torr cm = 0.757 Pa m (Dakin et al., Electra 32, 1974, Fig. 2 / Table; the value
#: quoted throughout the literature); the others are Dakin's fit to the measured air data,
#: V = 24.36 x + 6.72 sqrt(x) kV (x = p d in bar cm), at x = 0.005 ... 10 bar cm
#: (50 µm ... 10 cm at 1 atm), the range the fit was made over. Between rows: log-log
#: interpolation; between the minimum and 0.005 bar cm the table is the interpolation of
#: the two (no fit there); above 10 bar cm Dakin's law is extrapolated; below the
#: minimum the left branch is handled as for the Townsend curve (plateau at the
#: minimum, field emission).
EMPIRICAL_AIR = ((0.757, 327.0),) + tuple(
    (x * 1e3, _dakin_kv(x) * 1e3) for x in
    (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0))
#: p·d range [Pa m] the empirical table covers (its validity range)
EMPIRICAL_RANGE = (EMPIRICAL_AIR[0][0], EMPIRICAL_AIR[-1][0])


@dataclass(frozen=True)
class Paschen:
    """Paschen's curve of a gas at one pressure (SI): ``A`` [1/(Pa m)], ``B``
    [V/(Pa m)], ``gamma`` (secondary emission), ``pressure`` [Pa], ``longest_path``
    [m]: the longest discharge path the device offers (the left branch; inf: none)."""
    A: float = AIR_A
    B: float = AIR_B
    gamma: float = AIR_GAMMA
    pressure: float = ATMOSPHERE
    field_emission: float = FIELD_EMISSION_FIELD
    streamer_pd: float = STREAMER_PD
    longest_path: float = math.inf
    #: "townsend" (the formula with A, B, γ) or "empirical" (:data:`EMPIRICAL_AIR`)
    curve: str = "townsend"

    def __post_init__(self):
        if self.curve not in CURVES:
            raise ValueError(f"Paschen curve = {self.curve!r}: choose one of {CURVES}")
        if not (self.longest_path > 0.0):     # inf allowed: an unbounded gas
            raise ValueError(f"Paschen longest_path = {self.longest_path!r}: must be positive")
        for name in ("A", "B", "gamma", "pressure", "field_emission", "streamer_pd"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"Paschen {name} = {value!r}: must be a positive number")
        if self.streamer_pd <= self.pd_min:
            raise ValueError(f"streamer_pd = {self.streamer_pd:g} Pa m must exceed the "
                             f"Paschen minimum {self.pd_min:g} Pa m")

    @classmethod
    def from_scene(cls, scene) -> "Paschen":
        """The scene's ``[breakdown]`` constants (defaults: air at 1 atm) and its device's
        longest path (``scene.device.longest_path``: each cell shape's own); B at a
        contact run's ``[charge] relative_humidity_percent`` (:mod:`tengfield.humidity`:
        the given B is dry air's)."""
        bd = getattr(scene, "breakdown", None)
        path = scene.device.longest_path if getattr(scene, "device", None) else math.inf
        charge = getattr(scene, "charge", None)
        humid = 1.0     # [charge] relative_humidity_percent of a contact run: B rises
        if charge is not None and charge.from_contacts and charge.relative_humidity > 0.0:
            from .humidity import breakdown_factor
            humid = breakdown_factor(charge.relative_humidity)
        if bd is None:
            return cls(B=AIR_B * humid, longest_path=path)
        return cls(A=bd.paschen_A, B=bd.paschen_B * humid, gamma=bd.gamma,
                   pressure=bd.pressure, longest_path=path, curve=bd.paschen)

    def with_gamma(self, gamma: float) -> "Paschen":
        """The same curve with secondary-emission coefficient ``gamma``."""
        import dataclasses
        return dataclasses.replace(self, gamma=float(gamma))

    # -- the Townsend formula and its minimum ---------------------------------
    @property
    def log_term(self) -> float:
        """ln(ln(1 + 1/γ))."""
        return math.log(math.log1p(1.0 / self.gamma))

    @property
    def pd_min(self) -> float:
        """p·d [Pa m] of the curve's minimum: e^(1 + ln ln(1+1/γ)) / A (Townsend), the
        table's first row (empirical)."""
        if self.curve == "empirical":
            return EMPIRICAL_AIR[0][0]
        return math.exp(1.0 + self.log_term) / self.A

    @property
    def v_min(self) -> float:
        """Minimum breakdown voltage [V]: B·(p·d)_min (Townsend), 327 V (empirical)."""
        if self.curve == "empirical":
            return EMPIRICAL_AIR[0][1]
        return self.B * self.pd_min

    @property
    def d_min(self) -> float:
        """Gap [m] of the minimum at this pressure."""
        return self.pd_min / self.pressure

    @property
    def v_left(self) -> float:
        """Breakdown voltage [V] of the left branch below (p·d)_min: V_min when the
        longest path reaches (p·d)_min, else the Townsend value on the longest path
        (inf when no avalanche can sustain itself on it: vacuum)."""
        if self.pressure * self.longest_path >= self.pd_min:
            return self.v_min
        if self.curve == "empirical":   # the table has no left branch: Townsend's
            import dataclasses
            return dataclasses.replace(self, curve="townsend").v_left
        value = float(self.townsend(self.longest_path))
        return value if math.isfinite(value) else math.inf

    @property
    def d_field_emission(self) -> float:
        """Gap [m] below which the constant field-emission field applies: V_left / E_fe
        (V_min / E_fe unless the device is too small for the minimum)."""
        return self.v_left / self.field_emission

    @property
    def d_streamer(self) -> float:
        """Gap [m] above which the streamer law applies at this pressure."""
        return self.streamer_pd / self.pressure

    def townsend(self, d):
        """The bare Townsend formula [V] (NaN where its denominator is ≤ 0)."""
        pd = self.pressure * np.asarray(d, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            denominator = np.log(self.A * pd) - self.log_term
            return np.where(denominator > 0.0, self.B * pd / denominator, np.nan)

    def empirical(self, d):
        """V_b [V] of the empirical air table (:data:`EMPIRICAL_AIR`) at gap(s) ``d`` [m]:
        log-log interpolation in p·d, Dakin's law above the table, NaN below its minimum."""
        pd = self.pressure * np.asarray(d, dtype=float)
        table = np.asarray(EMPIRICAL_AIR)
        with np.errstate(divide="ignore", invalid="ignore"):
            inside = np.exp(np.interp(np.log(pd), np.log(table[:, 0]), np.log(table[:, 1])))
            x = pd / 1e5 * 1e2
            beyond = (DAKIN[0] * x + DAKIN[1] * np.sqrt(x)) * 1e3
        out = np.where(pd > table[-1, 0], beyond, inside)
        return np.where(pd >= table[0, 0], out, np.nan)

    def _dakin(self, pd):
        x = np.asarray(pd, dtype=float) / 1e5 * 1e2     # Pa m -> bar cm
        a, b = DAKIN
        return a * x + b * np.sqrt(x)

    # -- the curve used ---------------------------------------------------------
    def voltage(self, d):
        """Breakdown voltage V_b [V] of a gap ``d`` [m] (the whole curve, module docstring):
        continuous and non-decreasing in d; 0 at d = 0; NaN for NaN or negative d."""
        d = np.asarray(d, dtype=float)
        pd = self.pressure * d
        if self.curve == "empirical":
            with np.errstate(invalid="ignore", divide="ignore"):
                out = self.empirical(np.maximum(d, self.d_min))
                out = np.where(pd < self.pd_min, np.minimum(self.v_left, self.field_emission * d),
                               out)
                out = np.where(d >= 0.0, out, np.nan)
            return out if out.ndim else float(out)
        with np.errstate(invalid="ignore", divide="ignore"):
            townsend = self.townsend(np.clip(d, self.d_min, self.d_streamer))
            v_s = float(self.townsend(self.d_streamer))
            streamer = v_s * self._dakin(np.maximum(pd, self.streamer_pd)) / self._dakin(
                self.streamer_pd)
            out = np.where(pd > self.streamer_pd, streamer, townsend)
            out = np.where(pd < self.pd_min, np.minimum(self.v_left, self.field_emission * d), out)
            out = np.where(d >= 0.0, out, np.nan)
        return out if out.ndim else float(out)

    def regime(self, d) -> np.ndarray:
        """Which part of the curve applies at ``d`` [m]: one of :data:`REGIMES` per gap."""
        d = np.atleast_1d(np.asarray(d, dtype=float))
        out = np.full(d.shape, "townsend", dtype=object)
        out[d <= self.d_field_emission] = ("field-emission" if math.isfinite(self.v_left)
                                           else "vacuum")
        out[(d > self.d_field_emission) & (d < self.d_min)] = (
            "plateau" if self.v_left == self.v_min else "long-path")
        if self.curve == "empirical":
            out[d >= self.d_min] = "empirical"
        else:
            out[d > self.d_streamer] = "streamer"
        return out

    def to_json(self) -> dict:
        """The constants and the curve's landmarks (file-level units in the keys)."""
        if self.curve == "empirical":
            return {"curve": "empirical", "pressure_Pa": self.pressure, "V_min_V": self.v_min,
                    "d_min_m": self.d_min, "table_pd_Pa_m_V": [list(r) for r in EMPIRICAL_AIR],
                    "valid_pd_Pa_m": list(EMPIRICAL_RANGE),
                    "field_emission_field_V_per_m": self.field_emission,
                    "field_emission_below_m": self.d_field_emission,
                    "longest_path_m": self.longest_path if math.isfinite(self.longest_path)
                    else None,
                    "formula": "log-log interpolation of the table in p d; Dakin's law above "
                               "it; below its minimum the plateau V_min capped by E_fe d",
                    "source": "Dakin et al., Electra 32 (1974): uniform-field air at 20 C, "
                              "minimum 327 V at 0.757 Pa m; V = 24.36 x + 6.72 sqrt(x) kV "
                              "(x in bar cm) over 0.005-10 bar cm; gamma does not enter"}
        return {"curve": "townsend", "A_per_Pa_m": self.A, "B_V_per_Pa_m": self.B,
                "gamma": self.gamma, "secondary_emission": self.gamma,
                "pressure_Pa": self.pressure, "V_min_V": self.v_min, "d_min_m": self.d_min,
                "field_emission_field_V_per_m": self.field_emission,
                "field_emission_below_m": self.d_field_emission,
                "streamer_above_m": self.d_streamer, "streamer_pd_Pa_m": self.streamer_pd,
                "longest_path_m": self.longest_path if math.isfinite(self.longest_path)
                else None, "left_branch_V": self.v_left if math.isfinite(self.v_left) else None,
                "formula": "V_b = B p d / (ln(A p d) - ln(ln(1 + 1/gamma))) for "
                           "(p d)_min <= p d <= (p d)_s; below: V_min plateau (the "
                           "Townsend value of the longest path when p L < (p d)_min) "
                           "capped by E_fe d; "
                           "Dakin's uniform-field law scaled to continuity above",
                "source": "A, B: Raizer, Gas Discharge Physics (1991), Table 4.1; gamma = 0.01; "
                          "E_fe = 350 V/um: Peschot et al. (2014); streamer above 200 Torr cm: "
                          "Raizer sec. 12, law of Dakin et al., Electra 32 (1974)"}


def breakdown_voltage(d, pressure: float = ATMOSPHERE, *, A: float = AIR_A, B: float = AIR_B,
                      gamma: float = AIR_GAMMA):
    """V_b [V] of gap(s) ``d`` [m] at ``pressure`` [Pa] (:meth:`Paschen.voltage`)."""
    return Paschen(A=A, B=B, gamma=gamma, pressure=pressure).voltage(d)
