"""Physical constants shared by the whole package (SI)."""

G = 9.80665  # standard gravity [m/s^2]
EPS0 = 8.8541878128e-12  # vacuum permittivity [F/m]
