"""The registries answer what callers ask (issue #33): capabilities on the entries
(EXCITATIONS, MODELS, CIRCUITS), one lookup helper, and no call site comparing a
scene choice's name outside scene/ and the registries' own modules."""
import ast
import dataclasses
from pathlib import Path

import pytest

from tengfield import air_breakdown
from tengfield._registry import lookup
from tengfield.dynamics.excitation import EXCITATIONS, excitation_kind
from tengfield.dynamics.models import MODELS, model_of
from tengfield.electrical.circuits import CIRCUITS, circuit_for
from tengfield.errors import SceneError
from tengfield.fit.spec import run_columns
from tengfield.scene import default_scene

import plate_model as fx

SRC = Path(__file__).resolve().parents[2] / "src" / "tengfield"
#: the registries' own modules and the scene layer may name the choices (the shapes and
#: the [field] method table are scene/shapes/; the field cells ask that table, #41)
OWN = ("scene/", "dynamics/excitation.py", "dynamics/models.py", "electrical/circuits/",
       "_registry.py")


def _choice_comparisons() -> list[str]:
    names = set(EXCITATIONS) | set(MODELS) | set(CIRCUITS) | {"axisymmetric", "3d", "auto"}

    def strings(node):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return {node.value}
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return set().union(*(strings(e) for e in node.elts))
        return set()

    def name(node):
        return getattr(node, "attr", None) or getattr(node, "id", None)

    found = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel.startswith(OWN):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Compare) and name(node.left) in ("kind", "method", "model")
                    and any(strings(c) & names for c in node.comparators)):
                found.append(f"{rel}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_at_most_one_name_comparison_remains_with_its_reason():
    # 6 before the shape registry (#41): commands/field.py (2), field/cost.py, field/io.py,
    # accuracy_report/stages.py ask the [field] method table's entries now
    found = _choice_comparisons()
    assert len(found) <= 1, "\n".join(found)
    for hit in found:
        rel, line = hit.split(":")[:2]
        lines = (SRC / rel).read_text().splitlines()
        near = " ".join(lines[max(0, int(line) - 3):int(line)])
        assert "kept:" in near, f"{hit}: no '# kept: <reason>' comment"


def test_one_lookup_for_the_three_registries():
    for registry, key in ((EXCITATIONS, "[excitation] kind"), (MODELS, "[contact] model"),
                          (CIRCUITS, "[circuit] kind")):
        with pytest.raises(SceneError) as info:
            lookup(registry, "nonesuch", key)
        message = str(info.value)
        assert "\n" not in message and key in message and "'nonesuch'" in message
        assert all(repr(name) in message for name in registry)
    scene = default_scene()
    object.__setattr__(scene.circuit, "kind", "nonesuch")   # past the scene's own check
    with pytest.raises(SceneError, match=r"\[circuit\] kind = 'nonesuch'"):
        circuit_for(scene)


def test_excitation_capabilities_drive_the_callers(monkeypatch):
    # a sine has a band: sweeps, design bands and fit's amplitude scale; a record a length
    assert excitation_kind(default_scene()).periodic
    assert all(not (e.periodic and e.random) for e in EXCITATIONS.values())
    assert [k for k, e in EXCITATIONS.items() if e.recorded] == ["recorded"]
    from tengfield.design_study.answer import point_label
    assert point_label(33.0, 5e-4, "harmonics") == "33 Hz (harmonics)"
    # the caller asks the entry, not the name: a kind that says it is periodic gets a band
    monkeypatch.setitem(EXCITATIONS, "harmonics",
                        dataclasses.replace(EXCITATIONS["harmonics"], periodic=True))
    assert point_label(33.0, 5e-4, "harmonics") == "33 Hz / 0.5 mm"


def test_contact_model_capabilities():
    assert model_of(default_scene()).event_map
    assert [k for k, m in MODELS.items() if m.lateral] == ["3d"]
    assert [k for k, m in MODELS.items() if m.event_map] == ["impact"]


@pytest.mark.parametrize("kind, c_p, states", [
    ("open", 0.0, ("open",)), ("open", 100.0, ("open", "short")), ("short", 0.0, ("short",)),
    ("load", 0.0, air_breakdown.STATES), ("rectifier", 0.0, air_breakdown.STATES),
    ("series-rc", 0.0, air_breakdown.STATES)])
def test_breakdown_states_come_from_the_circuit_entry(kind, c_p, states):
    scene = fx.scene_with(circuit={"kind": kind, "parallel_capacitance_pF": c_p})
    assert air_breakdown.scene_states(scene) == states == circuit_for(scene).states(scene)


def test_a_circuit_has_a_load_where_it_reads_load_ohm():
    # summary.json's circuit block names load_ohm only where the entry has a load
    for name, entry in CIRCUITS.items():
        assert entry.has_load == ("load_ohm" in entry.keys), name
    assert CIRCUITS["load"].has_load and not CIRCUITS["rectifier"].has_load


def test_fit_columns_come_from_the_circuit_entry():
    assert run_columns("load")["V"] == ("V_load_V", "V") and CIRCUITS["load"].fit_load
    for kind in ("open", "short", "rectifier", "series-rc"):
        assert run_columns(kind)["V"] == ("V_oc_V", "V") and not CIRCUITS[kind].fit_load
    with pytest.raises(SceneError, match="circuit"):
        run_columns("nonesuch")
