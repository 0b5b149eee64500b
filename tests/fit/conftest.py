"""Fixtures of the fit tests: the plate-model surrogate (no dolfinx), cached per session."""
from __future__ import annotations


import pytest

import plate_model as fx

from tengfield.fit import reference_surrogate


@pytest.fixture(scope="session")
def surrogate_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("fit-surrogates")


@pytest.fixture(scope="session")
def plate_scene():
    """Default scene (1.5 mm, 20 Hz, e = 0.1: period-1 bouncing), σ = -8, C_p = 100 pF."""
    return fx.scene_with(circuit={"parallel_capacitance_pF": 100.0})


@pytest.fixture(scope="session")
def plate_surrogate(plate_scene, surrogate_cache):
    """(curves, σ_ref) of the plate model at the scene's σ (cached in a temporary dir)."""
    curves, sigma_ref, _ = reference_surrogate(plate_scene, cache_dir=surrogate_cache,
                                               solve=fx.plate_model_solve)
    return curves, sigma_ref
