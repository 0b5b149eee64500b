"""How the ball gets its charge: the registry of ``[charge] model`` (issue #51), one entry
per model, as :data:`tengfield.dynamics.models.MODELS` keeps the contact models.

Each entry carries what callers ask instead of comparing the model's name: whether the
run takes σ at the geometry's air-breakdown limit, whether the contacts make the charge
impact by impact, which ``[charge]`` keys it reads (a key it does not read is refused
where a study would vary it), and which commands run it (the others refuse it in one
line before the work: they would hold the charge constant). ``[device]`` σ =
``"breakdown"`` is the ``"breakdown"`` entry too. A new charge
model is one entry here, its keys in the scene schema and its physics in
:mod:`tengfield.source`.
"""
from __future__ import annotations

from dataclasses import dataclass

from ._registry import lookup

#: the commands that run a scene (what a charge model may or may not support)
COMMANDS = ("run", "sweep", "uncertainty", "design", "breakdown", "fit", "report", "map",
            "field", "dynamics", "precompute")


@dataclass(frozen=True)
class ChargeModel:
    """One ``[charge] model``: ``at_breakdown_limit`` (the run takes σ = −σ_max of its
    geometry), ``from_contacts`` (the contacts make the charge, impact by impact),
    ``keys`` (the ``[charge]`` keys it reads besides ``model``), ``commands`` (those that
    run it) and ``words`` (what it is, for messages)."""
    words: str
    at_breakdown_limit: bool = False
    from_contacts: bool = False
    keys: tuple = ()
    commands: tuple = COMMANDS

    def reads(self, key: str) -> bool:
        """Whether the ``[charge]`` key ``key`` acts under this model."""
        return key == "model" or key in self.keys


#: ``[charge] model`` -> its :class:`ChargeModel`
CHARGE_MODELS: dict[str, ChargeModel] = {
    # [device] sigma (SURFACE_CHARGE_KEY), the same at every instant
    "constant": ChargeModel("the constant [device] sigma"),
    # sigma = -sigma_max of the geometry's gap lines (tengfield.air_breakdown)
    "breakdown": ChargeModel("the geometry's air-breakdown limit", at_breakdown_limit=True),
    # made impact by impact (tengfield.source, tengfield.contact_run, docs/charge.md)
    "contact": ChargeModel(
        "the charge the contacts make", from_contacts=True,
        keys=("equilibrium_uC_per_m2", "efficiency", "initial_uC_per_m2", "leakage_time_s",
              "discharge", "relative_humidity_percent", "waveforms", "window_periods"),
        commands=("run", "sweep", "uncertainty", "design", "map", "field", "dynamics",
                  "precompute")),
}


def models_reading(key: str) -> str:
    """``'"contact"'``: the models under which the ``[charge]`` key ``key`` acts, quoted
    as a scene file writes them (for messages)."""
    return " or ".join(f'"{n}"' for n, e in CHARGE_MODELS.items() if e.reads(key))


def charge_model(name: str) -> ChargeModel:
    """The entry of ``[charge] model = name`` (an unknown name: one line naming the key)."""
    return lookup(CHARGE_MODELS, name, "[charge] model")


def charge_model_of(scene) -> ChargeModel:
    """The entry a scene runs with: ``[charge] model``, or ``"breakdown"`` where
    ``[device]``'s σ = ``"breakdown"`` says so."""
    from .quantities import stated_surface_charge

    if stated_surface_charge(scene) == "breakdown":
        return CHARGE_MODELS["breakdown"]
    charge = getattr(scene, "charge", None)
    return charge_model(getattr(charge, "model", "constant"))


def check_command(scene, command: str) -> None:
    """Refuse, in one line before the work, a scene whose charge model ``command`` does not
    run (e.g. ``tengfield fit`` of a contact-charged scene would hold the charge
    constant), naming the commands that do."""
    name = getattr(getattr(scene, "charge", None), "model", "constant") \
        if not isinstance(scene, dict) else (scene.get("charge") or {}).get("model")
    if name is None or name not in CHARGE_MODELS:
        return
    entry = CHARGE_MODELS[name]
    if command in entry.commands:
        return
    from .errors import SceneError
    others = [n for n, e in CHARGE_MODELS.items() if command in e.commands]
    runs = [c for c in entry.commands if c in ("run", "sweep", "uncertainty", "design")]
    raise SceneError(
        f'[charge] model = "{name}" is not supported by tengfield {command} yet (it would '
        "hold the charge constant): " + ", ".join(f"`tengfield {c}`" for c in runs)
        + " run it; here use [charge] model = " + " or ".join(f'"{n}"' for n in others)
        + " (docs/charge.md)")
