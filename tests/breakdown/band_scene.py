"""The coarse scene the breakdown band's command-line and study tests share (issue #38):
P1 fields at 1 mm, a 0.4 s run sampled at 5 kHz; σ as written (a number or
``'"breakdown"'``), ``extra`` sections after it (a string of TOML)."""


def band_scene(sigma: str, extra: str = "") -> str:
    """The scene text: ``[device]`` with σ = ``sigma``, ``[field]``, ``[run]``, then
    ``extra``."""
    return (f"\n[device]\nsurface_charge_uC_per_m2 = {sigma}\n"
            "[field]\ndegree = 1\nmesh_size_mm = 1.0\ntolerance = 0.03\n"
            "[run]\nduration_s = 0.4\nsettle_periods = 4\nsample_rate_hz = 5000\n" + extra)
