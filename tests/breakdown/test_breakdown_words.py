"""One vocabulary for the breakdown numbers (issue #53): the static limit σ_max (Paschen
without seeds, at the critical gap) at each γ, and the band's lower, estimate and upper,
each said against the static limit it differs from, so that no two numbers on one screen
read as the same thing (σ_max 25.9 and the estimate 26.07 were both "central"; 31.05 at
γ = 1e-4 and the band's upper 40.62 were both "upper"); the trajectory's time above 1 is
of its steady window, said so."""
from tengfield.air_breakdown.band import Band, Seeds, assumption_lines, gamma_line
from tengfield.commands.run import band_lines


def _band():
    return Band(lower=22.2e-6, estimate=26.07e-6, upper=40.62e-6, gamma_range=(1e-4, 0.1),
                gamma=0.01, gamma_lower=0.1, gamma_upper=1e-4, seeds=Seeds(),
                lower_position=0.188e-3, lower_gap=0.188e-3, upper_position=1.5e-3,
                upper_gap=1.5e-3, estimate_gap=0.2e-3,
                estimate_rule="seeded breakdowns per second reach the criterion",
                static_at_gamma=25.9e-6, seeds_at_estimate={}, paschen_curve="townsend",
                static_by_gamma={1e-4: 31.05e-6, 0.01: 25.9e-6, 0.1: 22.2e-6})


def test_the_gamma_line_gives_static_limits_not_a_range_that_reads_as_edges():
    line = gamma_line(_band())
    assert line.startswith("static limit sigma_max by gamma in [0.0001, 0.1]: ")
    assert "22.2 at gamma 0.1, 25.9 at gamma 0.01 (the scene's), 31.05 at gamma 0.0001" in line
    assert " to " not in line and "upper" not in line and "estimate" not in line


def test_each_edge_names_the_static_limit_it_differs_from():
    lines = assumption_lines(_band())
    assert "seeded, at or above the static limit 25.9 of the same gamma" in lines["estimate"]
    assert "static limit where the smaller gap is widest" in lines["upper"]
    assert "at the critical gap this gamma's static limit is 31.05" in lines["upper"]
    assert lines["lower"].startswith("lower    22.2 µC/m^2: the static limit")


def test_the_time_above_one_is_of_the_steady_window():
    summary = {"breakdown": {"band": {**_band().to_json()},
                             "trajectory": {"peak_gap_voltage_over_breakdown": 1.38,
                                            "time_above_breakdown_s": 0.465, "over_s": 0.5}}}
    (head, *_) = band_lines(summary)
    assert "over the 0.5 s steady window of the trajectory" in head
    assert "above 1 for 0.465 s of it" in head
