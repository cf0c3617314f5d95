# SPDX-License-Identifier: BSD-3-Clause
"""knnocc: 3D occupancy mapping (the compiled module's docstring replaces this one)."""

from ._knnocc import *  # noqa: F401,F403  (every public class and function)
from ._knnocc import __doc__, __version__, _last_points_input  # noqa: F401

del _knnocc  # noqa: F821  (the compiled part stays importable as knnocc._knnocc)
