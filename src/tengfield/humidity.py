"""The air's humidity and the contacts' charge: ``[charge] relative_humidity_percent``
(issue #52; with ``[charge] model = "contact"``).

No measured law for PTFE on copper is known (docs/charge.md): what follows is an
**assumption**, stated so that a study can draw the humidity and see what it moves. The
constants a scene gives (``[charge] equilibrium_uC_per_m2``, ``leakage_time_s`` and
``[breakdown]``'s Paschen B) are taken as those of **dry air** (RH = 0, the default: at 0
nothing changes); at a relative humidity RH in [0, 1]:

* the equilibrium density falls linearly to 0 at saturation (a water film screens the
  contact): ``sigma_eq(RH) = sigma_eq (1 - RH)``;
* the leakage time falls by one decade per :data:`LEAKAGE_DECADE_RH` of RH (the surface
  resistivity of fluoropolymers falls by decades from dry to humid air):
  ``tau(RH) = tau 10^(-RH / 0.2)``; ``tau = 0`` (no leakage) stays none;
* the breakdown voltage rises with the water vapour (about 2-3 % over 8-15 g/m^3 of
  absolute humidity): Paschen's ``B(RH) = B (1 + k AH)``, ``AH = RH x`` the saturation
  density at 20 °C (:data:`SATURATION_G_PER_M3`), ``k`` = :data:`BREAKDOWN_PER_G_PER_M3`
  (2.5 % over 7 g/m^3). V_b is proportional to B at a fixed p d (Townsend's form):
  the cap of ``[charge] discharge`` and every breakdown line follow it.

All three are pure functions of the dimensionless RH; SI in and out.
"""
from __future__ import annotations

#: RH per decade of the leakage time: tau falls 10x each 20 % of relative humidity
LEAKAGE_DECADE_RH = 0.2
#: water vapour at saturation [g/m^3] at 20 °C (the lab's air)
SATURATION_G_PER_M3 = 17.3
#: relative rise of the breakdown voltage per g/m^3 of absolute humidity (2.5 % over the
#: 8-15 g/m^3 the breakdown literature reports ~2-3 % for: 0.025 / 7)
BREAKDOWN_PER_G_PER_M3 = 0.025 / 7.0

#: the law in one line (the summary's ``charge.humidity_law``, docs/charge.md)
LAW = ("an assumption (no PTFE-copper law known): the given sigma_eq, tau and Paschen B "
       "are dry air's; sigma_eq (1 - RH), tau 10^(-RH/0.2), B (1 + 0.00357/(g/m^3) x RH x "
       "17.3 g/m^3)")


def humid_equilibrium(equilibrium: float, humidity: float) -> float:
    """sigma_eq [C/m^2] at relative humidity ``humidity`` in [0, 1] from the dry value."""
    return equilibrium * (1.0 - humidity)


def humid_leakage_time(leakage_time: float, humidity: float) -> float:
    """tau [s] at relative humidity ``humidity`` from the dry value (0: no leakage, kept)."""
    return leakage_time * 10.0 ** (-humidity / LEAKAGE_DECADE_RH)


def absolute_humidity(humidity: float) -> float:
    """Water vapour [g/m^3] of air at relative humidity ``humidity`` and 20 °C."""
    return humidity * SATURATION_G_PER_M3


def breakdown_factor(humidity: float) -> float:
    """V_b(RH) / V_b(dry) at a fixed p d: the factor on Paschen's B."""
    return 1.0 + BREAKDOWN_PER_G_PER_M3 * absolute_humidity(humidity)
