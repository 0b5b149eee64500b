"""Scene files: defaults, units, and one clear error per kind of bad input."""
import math

import pytest

from tengfield.scene import (G, SceneError, check_field, default_scene, default_text, load_scene,
                             parse_scene)


def test_default_scene_is_the_paper_device():
    s = default_scene()
    d = s.device
    assert d.ball_diameter == pytest.approx(7e-3)
    assert d.stroke == pytest.approx(3e-3)
    assert d.plate_spacing == pytest.approx(10e-3)
    assert d.tube_inner_radius == pytest.approx(4e-3)
    assert d.tube_outer_radius == pytest.approx(5.5e-3)
    assert d.surface_charge == pytest.approx(-8e-6)
    assert d.ball_charge == pytest.approx(-8e-6 * math.pi * 49e-6)
    assert s.excitation.frequency == 20.0 and s.excitation.amplitude == pytest.approx(1.5e-3)
    assert s.excitation.gamma == pytest.approx(1.5e-3 * (40 * math.pi) ** 2 / G)
    assert s.is_axisymmetric


def test_default_text_round_trips():
    assert parse_scene(default_text()) == default_scene()


def test_field_hash_tracks_only_field_inputs():
    s = default_scene()
    h = s.field_hash()
    assert s.with_values(excitation={"frequency_hz": 33.0}).field_hash() == h
    assert s.with_values(contact={"restitution": 0.3}).field_hash() == h
    assert s.with_values(circuit={"kind": "load", "load_ohm": 1e6}).field_hash() == h
    assert s.with_values(device={"cells": 91}).field_hash() == h
    assert s.with_values(device={"ball_permittivity": 2.0}).field_hash() != h
    assert s.with_values(field={"mesh_size_mm": 0.4}).field_hash() != h
    # sigma is not a field input: a cached surrogate is scaled to it (issue #28)
    assert s.with_values(device={"surface_charge_uC_per_m2": -9.0}).field_hash() == h
    assert s.with_values(device={"surface_charge_uC_per_m2": 8.0}).field_hash() == h
    assert s.with_values(device={"surface_charge_uC_per_m2": "breakdown"}).field_hash() == h


BAD = [
    ("[device]\nball_diameter_mm = -7\n", ["ball_diameter_mm", "-7", "[1e-06, 10000]"]),
    ("[device]\nball_diameter_mm = 0\n", ["ball_diameter_mm", "0"]),
    ("[device]\nstroke_mm = nan\n", ["stroke_mm", "nan", "not finite"]),
    ("[device]\nball_diameter_mm = 8.0\n", ["ball_diameter_mm", "8", "does not fit", "8) mm"]),
    ("[device]\nelectrode_radius_mm = 6.0\n", ["electrode_radius_mm", "6", "larger than the plate"]),
    ("[contact]\nrestitution = 1.2\n", ["restitution", "1.2", "[0, 1]"]),
    ("[contact]\nrestitution = -0.1\n", ["restitution", "-0.1"]),
    ("[excitation]\nfrequency_hz = 0\n", ["frequency_hz", "0", "[1e-06, 1e+09]"]),
    ("[excitation]\nfrequency_hz = -5\n", ["frequency_hz", "-5"]),
    ("[run]\nduration_s = 0\n", ["duration_s", "0"]),
    ("[run]\nduration_s = -1\n", ["duration_s", "-1"]),
    ("[devcie]\nstroke_mm = 3\n", ["devcie", "did you mean 'device'"]),
    ("[device]\nball_diamter_mm = 7\n", ["ball_diamter_mm", "did you mean 'ball_diameter_mm'"]),
    ("[contact]\nmodel = 'sofft'\n", ["model", "sofft", "'impact', 'soft'", "did you mean 'soft'"]),
    ("[device]\nstroke_mm = 3\nball_diameter_mm = \n", ["malformed TOML", "line 3"]),
    ("[device]\nstroke_mm = 'three'\n", ["stroke_mm", "'three'", "number"]),
    ("[device]\ncells = 2.5\n", ["cells", "2.5", "whole"]),
    ("[initial]\ngap_mm = 4\n", ["[initial] gap_mm", "4", "[0, 3]"]),
    ("[field]\nmesh_size_mm = 0\n", ["mesh_size_mm", "0"]),
    ("[field]\ndomain_radius_mm = 5\n", ["domain_radius_mm", "5", "must exceed"]),
    ("[circuit]\nload_ohm = -10\n", ["load_ohm", "-10"]),
    ("[circuit]\nparallel_capacitance_pF = -1\n", ["parallel_capacitance_pF", "-1"]),
    ("[circuit]\nreference = 'ground'\n", ["reference", "'ground'", "'floating'"]),
    ("[run]\nsettle_periods = 100\nduration_s = 1\n", ["settle_periods", "100", "steady window"]),
    ("[excitation]\nkind = 'recorded'\n", ["file"]),
]


@pytest.mark.parametrize("text,needles", BAD)
def test_bad_input_names_key_value_and_range(text, needles):
    with pytest.raises(SceneError) as info:   # field-only values: at the field stage
        check_field(parse_scene(text))
    msg = str(info.value)
    for n in needles:
        assert n in msg, (n, msg)


def _recorded(tmp_path, body):
    (tmp_path / "table.csv").write_text(body)
    scene = tmp_path / "s.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'table.csv'\n")
    return scene


def test_recorded_file_missing(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'nope.csv'\n")
    with pytest.raises(SceneError, match="nope.csv.*no such file"):
        load_scene(scene)


def test_recorded_file_unsorted(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,0\n0.05,0\n0.2,0\n0.3,0\n0.4,0\n")
    with pytest.raises(SceneError, match="not strictly increasing at data row 3"):
        load_scene(s)


def test_recorded_file_nan(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,nan\n0.2,0\n0.3,0\n0.4,0\n0.5,0\n")
    with pytest.raises(SceneError, match="NaN or inf at data row 2"):
        load_scene(s)


def test_recorded_file_wrong_column(tmp_path):
    s = _recorded(tmp_path, "time_s,displacment_m\n0,0\n0.1,0\n0.2,0\n0.3,0\n")
    with pytest.raises(SceneError, match="did you mean 'displacment_m'"):
        load_scene(s)


def test_recorded_file_ok(tmp_path):
    s = _recorded(tmp_path, "time_s,displacement_m\n0,0\n0.1,1e-3\n0.2,0\n0.3,-1e-3\n0.4,0\n"
                            "0.5,1e-3\n")
    scene = load_scene(s)
    assert scene.excitation.times.tolist() == [0, 0.1, 0.2, 0.3, 0.4, 0.5]


def test_missing_scene_file():
    with pytest.raises(SceneError, match="does not exist"):
        load_scene("/nonexistent/scene.toml")


# -- #8.1: domain_radius_mm = "auto", field-only values checked at the field stage ----------
def test_auto_domain_radius_is_twenty_mm_for_the_paper_device():
    scene = default_scene()
    assert scene.raw["field"]["domain_radius_mm"] == "auto"
    assert scene.field.domain_radius == 20.0 * 1e-3          # bit-identical to the old 20.0
    assert scene.field_inputs()["field"]["domain_radius_mm"] == 20.0
    explicit = default_scene().with_values(field={"domain_radius_mm": 20.0})
    assert explicit.field == scene.field and explicit.field_hash() == scene.field_hash()


@pytest.mark.parametrize("device", [
    {"stroke_mm": 30.0},                                          # tall
    {"tube_outer_radius_mm": 100.0, "tube_inner_radius_mm": 90.0,
     "electrode_radius_mm": 100.0},                                # wide
    {"stroke_mm": 0.5, "ball_diameter_mm": 0.7, "tube_inner_radius_mm": 0.4,
     "tube_outer_radius_mm": 0.55, "electrode_radius_mm": 0.4,
     "plate_thickness_mm": 0.2},                                   # the paper's device / 10
])
def test_auto_domain_radius_scales_with_the_device(device):
    scene = default_scene().with_values(device=device)
    check_field(scene)
    b = scene.device.bounding_radius
    assert 2.2 * b <= scene.field.domain_radius <= 2.2 * b * 1.1


def test_dynamics_only_scene_never_fails_on_a_field_value():
    from tengfield.dynamics import simulate

    text = ("[device]\nstroke_mm = 30\n[field]\ndomain_radius_mm = 5\nmesh_size_mm = 0\n"
            "degree = 9\nmethod = 'fem'\n[run]\nduration_s = 0.2\nsettle_periods = 1\n")
    scene = parse_scene(text)                       # no error at load
    assert len(scene.field_problems) == 4
    result = simulate(scene)        # the dynamics never looks at [field]
    assert result.t.size > 0
    with pytest.raises(SceneError) as info:         # the field stage names every problem
        check_field(scene)
    for needle in ("domain_radius_mm = 5", "mesh_size_mm = 0", "degree = 9", "method = 'fem'"):
        assert needle in str(info.value)
    assert "\n" not in str(info.value)
    with pytest.raises(SceneError, match="domain_radius_mm = 5"):
        scene.field.mesh_size                       # any use of a field value refuses too
    with pytest.raises(SceneError, match="mesh_size_mm = 0"):
        scene.field_hash()                          # so `tengfield scene FILE` reports them


def test_explicit_field_overrides_are_checked_at_once():
    with pytest.raises(SceneError, match="mesh_size_mm = -1"):
        default_scene().with_values(field={"mesh_size_mm": -1.0})
    with pytest.raises(SceneError, match="expected a number or 'auto'"):
        default_scene().with_values(field={"domain_radius_mm": "big"})


# -- #8.7: geometry/mesh ranges relative to the geometry (check_field) -----------------------
@pytest.mark.parametrize("section,values,needles", [
    ("device", {"stroke_mm": 0.01}, ["stroke_mm = 0.01", "too small for a field solve", ">= 0.114 mm"]),
    ("device", {"ball_diameter_mm": 1e-6}, ["ball_diameter_mm = 1e-06", ">= 0.00652 mm"]),
    ("field", {"mesh_size_mm": 0.001}, ["mesh_size_mm = 0.001", "too fine", ">= 0.075 mm"]),
    ("field", {"domain_radius_mm": 1e6}, ["domain_radius_mm = 1e+06", "too large", "<= 445 mm"]),
    ("field", {"domain_radius_mm": 10.0}, ["domain_radius_mm = 10", "must exceed 10.7 mm"]),
    ("field", {"ball_offset_mm": 0.6}, ["ball_offset_mm = 0.6", "[0, 0.5] mm"]),
])
def test_geometry_relative_field_ranges(section, values, needles):
    scene = parse_scene("\n".join([f"[{section}]"] + [f"{k} = {v!r}" for k, v in values.items()]))
    with pytest.raises(SceneError) as info:
        check_field(scene)
    for n in needles:
        assert n in str(info.value), (n, str(info.value))


def test_field_ranges_admit_the_edges_the_solvers_are_tested_at():
    check_field(default_scene().with_values(device={"ball_diameter_mm": 7.999}))   # 0.5 µm clearance
    check_field(default_scene().with_values(field={"mesh_size_mm": 0.075}))
    check_field(default_scene().with_values(field={"domain_radius_mm": 445.0}))
    check_field(default_scene().with_values(field={"ball_offset_mm": 0.5, "mesh_size_mm": 0.375}))


# -- #8.4: recorded excitation, the same steady-window rule as sine -------------------------
def test_recorded_settle_beyond_duration_is_refused(tmp_path):
    t = [i * 1e-3 for i in range(2001)]
    rows = "".join(f"{x!r},{1e-3 * math.sin(2 * math.pi * 20 * x)!r}\n" for x in t)
    (tmp_path / "table.csv").write_text("time_s,displacement_m\n" + rows)
    scene = tmp_path / "s.toml"
    scene.write_text("[excitation]\nkind = 'recorded'\nfile = 'table.csv'\n"
                     "[run]\nduration_s = 1.0\nsettle_periods = 20\n")
    with pytest.raises(SceneError, match=r"settle_periods = 20 leaves no steady window.*"
                                         r"= 1 s must be < duration_s = 1"):
        load_scene(scene)
    scene.write_text(scene.read_text().replace("settle_periods = 20", "settle_periods = 19"))
    assert load_scene(scene).run.settle_periods == 19


# -- #8.5: encodings, BOM, directories --------------------------------------------------------
@pytest.mark.parametrize("blob,needle", [
    ("[device]\n# Kugel aus PTFE, Durchmesser 7 mm (\u00e9)\nstroke_mm = 3\n".encode("latin-1"),
     "not UTF-8 text (byte 0xe9"),
    ("[device]\nstroke_mm = 3\n".encode("utf-16"), "UTF-16"),
    (bytes(range(256)) * 4, "binary data"),
    (b"\x00\x00\x00[device]", "NUL"),
])
def test_scene_not_utf8_is_one_line(tmp_path, blob, needle):
    path = tmp_path / "s.toml"
    path.write_bytes(blob)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_utf8_bom_is_accepted_in_toml_and_csv_headers(tmp_path):
    path = tmp_path / "s.toml"
    path.write_bytes(b"\xef\xbb\xbf[device]\nstroke_mm = 2.5\n")
    assert load_scene(path).device.stroke == pytest.approx(2.5e-3)
    (tmp_path / "table.csv").write_bytes(
        b"\xef\xbb\xbftime_s,displacement_m\n" + b"".join(b"%g,0\n" % (0.1 * i) for i in range(12)))
    path.write_text("[excitation]\nkind = 'recorded'\nfile = 'table.csv'\n"
                    "[run]\nduration_s = 1\nsettle_periods = 1\n")
    assert load_scene(path).excitation.times.size == 12


def test_directory_as_scene_says_so(tmp_path):
    with pytest.raises(SceneError, match="is a directory"):
        load_scene(tmp_path)


# -- #8.6: sizes with upper bounds, the product named ----------------------------------------
@pytest.mark.parametrize("text,needles", [
    ("[run]\nduration_s = 1e6\n",
     ["duration_s x sample_rate_hz = 1e+06 x 20000 = 2e+10 samples", "allowed <= 2e+07"]),
    ("[run]\nsample_rate_hz = 1e9\n", ["= 1e+09 samples", "allowed <= 2e+07"]),
    ("[excitation]\nfrequency_hz = 1e9\n[run]\nsettle_periods = 0\n",
     ["duration_s x [excitation] frequency_hz = 1 x 1e+09 = 1e+09 excitation periods",
      "1.6e+10 impact-map events", "allowed <= 1e+06 periods"]),
])
def test_work_beyond_the_limits_is_refused_before_allocating(text, needles):
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    for n in needles:
        assert n in str(info.value), (n, str(info.value))


def test_work_limits_do_not_bite_real_use():
    parse_scene("[run]\nduration_s = 1000\n")                          # 2e7 samples at 20 kHz
    parse_scene("[run]\nduration_s = 100\nsample_rate_hz = 200000\n")  # 2e7 samples
    parse_scene("[excitation]\nfrequency_hz = 2000\n[run]\nduration_s = 500\n"
                "sample_rate_hz = 40000\n")                            # 1e6 periods


# -- #8.9: recorded CSV rows, empty file -----------------------------------------------------
@pytest.mark.parametrize("rows", [0, 1, 4, 5])
def test_recorded_file_with_too_few_rows_names_the_key_and_count(tmp_path, rows):
    body = "time_s,displacement_m\n" + "".join(f"{0.1 * i},0\n" for i in range(rows))
    s = _recorded(tmp_path, body)
    with pytest.raises(SceneError, match=rf"\[excitation\] file = 'table.csv' has {rows} data "
                                         r"rows: at least 6 are needed"):
        load_scene(s)


@pytest.mark.parametrize("body", ["", "\n\n  \n"])
def test_recorded_empty_file_is_one_line_without_warnings(tmp_path, body, recwarn):
    s = _recorded(tmp_path, body)
    with pytest.raises(SceneError, match=r"\[excitation\] file = 'table.csv' is empty"):
        load_scene(s)
    assert not recwarn.list


def test_recorded_six_rows_run(tmp_path):
    from tengfield.dynamics import simulate

    body = "time_s,displacement_m\n" + "".join(f"{0.1 * i},0\n" for i in range(6))
    s = _recorded(tmp_path, body)
    s.write_text(s.read_text() + "[run]\nduration_s = 0.4\nsettle_periods = 1\n")
    assert simulate(load_scene(s)).regime.name == "rest"


def test_scene_with_field_problems_travels_to_worker_processes():
    import copy
    import pickle

    scene = parse_scene("[field]\nmesh_size_mm = 0\n")
    for clone in (pickle.loads(pickle.dumps(scene)), copy.deepcopy(scene)):
        assert clone == scene and clone.field_problems == scene.field_problems
        assert clone.excitation.frequency == 20.0
