"""The planar contact-separation device as breakdown ``Lines`` (test fixture only): its
limits are known in closed form (Zi et al., Adv. Funct. Mater. 27:1700049, 2017)."""
import numpy as np

from tengfield import air_breakdown
from tengfield.scene import EPS0
from tengfield.surrogate import lobatto_positions


def planar_lines(x_max: float, d0: float, count: int = 33) -> air_breakdown.Lines:
    """Per unit area: lower electrode at 0, air gap x, the charged surface, a dielectric of
    thickness d0 eps_r on the upper electrode (the 'ball' is the charged sheet); its one
    line stands for a column of 1 m^2 (``foot_areas``: the over-stressed volume is the
    gap x per m^2)."""
    x = lobatto_positions(x_max, count)
    c = EPS0 / (x + d0)
    C = np.stack([np.stack([c, -c], -1), np.stack([-c, c], -1)], -2)
    fractions = np.column_stack([-d0 / (x + d0), -x / (x + d0)])
    # potential of the sheet with both electrodes grounded: sigma / (eps0/x + eps0/d0)
    phi1 = x * d0 / (EPS0 * (x + d0))
    lower = np.column_stack([phi1, d0 / (x + d0), x / (x + d0)])
    basis = np.stack([lower, np.full_like(lower, np.nan)], axis=1)[:, :, None, :]
    return air_breakdown.Lines(positions=x, capacitance=C, fractions=fractions, ball_area=1.0,
                           basis=basis, angles=np.array([0.0]), ball_radius=0.0, stroke=x_max,
                           electrode_radius=1.0, sides=(True, False),
                           foot_areas=np.array([1.0]))
