"""The schema is the one place a scene key is declared (issue #22): the surrogate cache
hash follows its ``field`` flags, and the dataclasses check themselves against it."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tengfield.errors import SceneError
from tengfield.scene import Device, Scene, default_scene
from tengfield.scene.schema import FIELD_KEYS, SCHEMA

#: the field hash of the default scene (every cached surrogate of it is keyed by this;
#: FIELD_SCHEMA 2: sigma left the hash, issue #28)
DEFAULT_FIELD_HASH = "b60e9f08787bcb2dcfe3f4759b8cac5b3bf8488ea49dd5adb3b2c65053007eff"

#: keys whose change needs other keys set to build a valid scene (in both scenes compared)
RECORDED = {"kind": "recorded", "file": "table.csv"}
COMPANIONS = {
    ("charge", "relative_humidity_percent"): {"model": "contact"},   # RH acts with contacts
    ("excitation", "file"): dict(RECORDED),
    ("excitation", "time_column"): dict(RECORDED),
    ("excitation", "signal_column"): dict(RECORDED),
    ("excitation", "signal"): dict(RECORDED),
    ("excitation", "smoothing_hz"): dict(RECORDED),
    ("excitation", "signal_x_column"): dict(RECORDED),
    ("excitation", "signal_y_column"): dict(RECORDED),
    ("excitation", "psd_file"): {"kind": "random", "psd_file": "psd.csv"},
    ("excitation", "band_hz"): {"kind": "random", "band_hz": [10.0, 100.0],
                                "rms_acceleration_m_per_s2": 1.0},
    ("excitation", "rms_acceleration_m_per_s2"): {"kind": "random", "band_hz": [10.0, 100.0],
                                                  "rms_acceleration_m_per_s2": 1.0},
    # a lateral noise level needs the noise's spectrum (a sine refuses it)
    ("excitation", "rms_acceleration_x_m_per_s2"): {"kind": "random", "band_hz": [10.0, 100.0],
                                                    "rms_acceleration_m_per_s2": 1.0},
    ("excitation", "rms_acceleration_y_m_per_s2"): {"kind": "random", "band_hz": [10.0, 100.0],
                                                    "rms_acceleration_m_per_s2": 1.0},
    ("run", "realisations"): {"excitation": {"kind": "random", "band_hz": [10.0, 100.0],
                                             "rms_acceleration_m_per_s2": 1.0}},
    # the first other shape, "hexagonal", is a 3D cell (method = "3d"); a spherical
    # shell's stroke is cavity - ball diameter (20 - 7 mm): stroke_mm equal to it
    ("device", "shape"): {"stroke_mm": 13.0, "field": {"method": "3d"}},
    ("array", "connection"): {"cells": 2, "circuit": {"kind": "rectifier"}},
    ("array", "initial_phase_spread_deg"): {"cells": 2},
    ("array", "restitution_spread"): {"cells": 2},
    ("array", "initial_velocity_spread_m_per_s"): {"cells": 2},
}
#: the alternative value of a key, where the generic candidates do not build
ALTERNATIVES = {
    ("breakdown", "gamma_range"): [(1e-3, 0.05)],
    ("excitation", "file"): ["table2.csv"],
    ("excitation", "time_column"): ["t2_s"],
    ("excitation", "signal_column"): ["d2_m"],
    ("excitation", "signal_x_column"): ["x_m"],
    ("excitation", "signal_y_column"): ["x_m"],
    ("excitation", "psd_file"): ["psd2.csv"],
    ("excitation", "band_hz"): [[10.0, 200.0]],
    ("field", "domain_radius_mm"): [25.0],
    # a reader takes at least 2 readings in the steady window (1 Hz would take fewer)
    ("instrument", "sample_rate_hz"): [1000.0],
}


def _files(directory):
    t = np.arange(400) / 1000.0
    y = 1e-3 * np.sin(2 * np.pi * 20.0 * t)
    rows = "".join(f"{float(a)!r},{float(b)!r},{float(a)!r},{float(b)!r},{float(b)!r}\n" for a, b in zip(t, y))
    for name in ("table.csv", "table2.csv"):
        (directory / name).write_text("time_s,displacement_m,t2_s,d2_m,x_m\n" + rows)
    for name, level in (("psd.csv", 1e-3), ("psd2.csv", 2e-3)):
        (directory / name).write_text(f"frequency_hz,psd_g2_per_hz\n10,{level}\n100,{level}\n")


def _candidates(spec):
    d = spec.default
    if spec.type is str:
        return [o for o in (spec.check[1] if spec.check else ("other",)) if o != d]
    if spec.type is tuple:
        return []
    _, lo, hi, lo_open, hi_open = spec.check[:5]
    if spec.type is int:
        values = [d + 1, d - 1, d + 2]
    else:
        values = [d * 1.05, d * 0.95, d + 0.05, d - 0.05, d + 1.0, 0.5 * (lo + hi)]
    return [v for v in values if v != d and math.isfinite(v)
            and (lo < v if lo_open else lo <= v) and (v < hi if hi_open else v <= hi)]


def _pair(base, sec, key, tmp_path):
    """Two valid scenes differing only in ``[sec] key`` (with its companions set in both)."""
    spec = SCHEMA[sec][key]
    extra = dict(COMPANIONS.get((sec, key), {}))
    sections = {s: extra.pop(s) for s in list(extra) if s in SCHEMA}
    sections.setdefault(sec, {}).update(extra)
    scene = Scene.from_dict({**base, **{s: {**base.get(s, {}), **v} for s, v in sections.items()}},
                            base_dir=tmp_path)
    alternatives = ALTERNATIVES[sec, key] if (sec, key) in ALTERNATIVES else _candidates(spec)
    for value in alternatives:
        try:
            other = scene.with_values(**{sec: {key: value}})
        except SceneError:
            continue
        return scene, other
    raise AssertionError(f"no alternative value of [{sec}] {key} builds a valid scene")


def test_the_default_field_hash_is_unchanged():
    assert default_scene().field_hash() == DEFAULT_FIELD_HASH


def test_field_keys_are_the_flagged_keys():
    flagged = {(sec, key) for sec, keys in SCHEMA.items() for key, spec in keys.items()
               if spec.field}
    assert flagged == {(sec, key) for sec, keys in FIELD_KEYS.items() for key in keys}
    assert set(FIELD_KEYS) == {"device", "field"}   # no empty sections in the hash


@pytest.mark.parametrize("sec,key", [(sec, key) for sec, keys in SCHEMA.items() for key in keys])
def test_a_key_changes_the_field_hash_exactly_when_flagged(tmp_path, monkeypatch, sec, key):
    _files(tmp_path)
    monkeypatch.chdir(tmp_path)   # the files the scenes name
    base = {s: dict(v) for s, v in default_scene().raw.items()}
    scene, other = _pair(base, sec, key, tmp_path)
    attr = SCHEMA[sec][key].attr
    assert getattr(getattr(other, sec), attr) != getattr(getattr(scene, sec), attr)
    changed = other.field_hash() != scene.field_hash()
    assert changed == SCHEMA[sec][key].field, (sec, key)


def test_dataclasses_built_from_python_check_their_keys():
    device = default_scene().device
    values = {name: getattr(device, name) for name in device.__dataclass_fields__}
    with pytest.raises(SceneError, match=r"Device.ball_diameter = -1 is out of range: "
                                         r"\[device\] ball_diameter_mm = -1000 is allowed "
                                         r"\[1e-06, 10000\]"):
        Device(**{**values, "ball_diameter": -1})
    with pytest.raises(SceneError, match=r"Device.cells = 2.5: expected a whole number"):
        Device(**{**values, "cells": 2.5})
    with pytest.raises(SceneError, match="does not fit the tube"):
        Device(**{**values, "ball_diameter": 9e-3})
    assert Device(**values) == device
