"""The circuit registry (tengfield.electrical.circuits): one entry per [circuit] kind."""
import ast
from pathlib import Path

from tengfield import electrical
from tengfield.electrical.circuits import CIRCUITS, Circuit, all_columns, circuit_for
from tengfield.scene.schema import SCHEMA

import plate_model as fx

SRC = Path(__file__).resolve().parents[2] / "src" / "tengfield"


def test_the_schema_offers_exactly_the_registered_kinds():
    # the scene layer cannot import electrical/: its tuple is held equal to the registry
    kind = SCHEMA["circuit"]["kind"]
    assert set(kind.check[1]) == set(CIRCUITS)
    assert kind.default in CIRCUITS


def test_every_entry_is_a_circuit_with_known_keys():
    keys = set(SCHEMA["circuit"])
    for name, entry in CIRCUITS.items():
        assert isinstance(entry, Circuit) and entry.name == name
        assert set(entry.keys) <= keys, name
        assert not set(entry.columns) & set(electrical.WAVEFORM_COLUMNS), name
    assert all_columns()[:3] == electrical.LOAD_COLUMNS        # waveforms.csv's order
    assert circuit_for(fx.scene_with(circuit={"kind": "rectifier"})) is CIRCUITS["rectifier"]


def test_no_kind_chains_outside_the_registry():
    # pipeline, array, io and sweep ask the entry, not `circuit.kind == ...`
    for name in ("pipeline.py", "array.py", "io.py", "sweeps.py"):
        text = (SRC / name).read_text()
        assert "circuit.kind ==" not in text and "kind == \"rectifier\"" not in text, name


def test_the_scene_layer_does_not_import_electrical():
    for path in (SRC / "scene").glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                assert "electrical" not in (node.module or ""), path
