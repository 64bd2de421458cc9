"""Units: the code works in SI (m, rad, s); papers give mm and degrees. Converted at the edge with these."""

import math

__all__ = ["DEG", "MM"]

#: one degree in radians
DEG = math.pi / 180
#: one millimetre in metres
MM = 1e-3
