"""report.md (issue #53): the recommendations table's last row broke the table (its note
was written after the closing pipe). Every row has the header's cells; a note is a cell of
its own, its pipes escaped."""
import re
from types import SimpleNamespace

from tengfield.accuracy_report.output import markdown
from tengfield.accuracy_report.plan import QUANTITIES
from tengfield.scene import default_scene


def _recommendation(target, note):
    return SimpleNamespace(
        target=target, field={"method": "remesh", "degree": 1, "mesh_size_mm": 1.0,
                              "far_field": "box", "tolerance": 1e-3},
        sample_rate_hz=5000.0, positions=17, predicted_error=target / 2,
        measured_errors={q: target / 3 for q in QUANTITIES}, measured_wall_time_s=1.5,
        reached=not note, note=note)


def _cells(row: str) -> int:
    return len(re.split(r"(?<!\\)\|", row.strip())) - 2


def test_every_table_row_has_the_headers_cells_and_a_note_is_its_own_cell():
    report = SimpleNamespace(
        scene=default_scene(), fast=True, trajectory={"regime": "bounce"}, wall_time_s=20.0,
        references={}, plan=SimpleNamespace(circuit_refinement=4), rows=[],
        recommendations=[_recommendation(1e-2, ""),
                         _recommendation(1e-3, "no measured combination reaches 1e-3 | the "
                                               "field's share\nis the limit")])
    text = markdown(report, {})
    table = [line for line in text.splitlines() if line.startswith("| target")]
    assert table
    lines = text.splitlines()
    start = lines.index(table[0])
    rows = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        rows.append(line)
    assert len(rows) == 4                         # header, rule, two recommendations
    assert {_cells(r) for r in rows} == {_cells(rows[0])}, rows
    assert rows[-1].endswith("the field's share is the limit |")
    assert "reaches 1e-3 \\| the" in rows[-1]
