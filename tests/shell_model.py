"""The spherical shell the shell tests share: a 20 mm cavity, 2 mm of ε = 3 shell, a 2 mm
equatorial band, an 8 mm PTFE ball (stroke 12 mm); as scene keys (``SHELL``) and as the
``[device]`` block of a scene file (:func:`shell_device_toml`)."""

SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 20.0, "shell_thickness_mm": 2.0,
         "electrode_band_mm": 2.0, "ball_diameter_mm": 8.0, "wall_permittivity": 3.0,
         "surface_charge_uC_per_m2": -50.0}


def shell_device_toml(sigma: str = "-50", extra: str = "") -> str:
    """The ``[device]`` section of the shell, σ as written (``"{sigma}"`` keeps a
    ``str.format`` field), ``extra`` lines after it; ends with a blank line."""
    return ("[device]\nshape = \"spherical-shell\"\ncavity_diameter_mm = 20\n"
            "shell_thickness_mm = 2\nelectrode_band_mm = 2\nball_diameter_mm = 8\n"
            f"wall_permittivity = 3.0\nsurface_charge_uC_per_m2 = {sigma}\n{extra}\n")
