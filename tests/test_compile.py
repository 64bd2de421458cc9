"""The kernels compile without numba's slow paths: a fresh clone compiles every kernel on its first run
(``paragym leaderboard --quick``, the README's main job), so a kernel's compile time is paid by every new user."""

import os
import subprocess
import sys
import textwrap

import pytest

# compiles, in a numba cache of its own (cold), the kernels that once copied arrays into slices, and prints every
# function numba compiled on the way
_SCRIPT = textwrap.dedent("""
    from numba.core import event

    compiled = []

    class Seen(event.Listener):
        def on_start(self, ev):
            compiled.append(ev.data["dispatcher"].py_func.__qualname__)

        def on_end(self, ev):
            pass

    event.register("numba:compile", Seen())

    import numpy as np

    from paragym.mechanisms import hybrid, tripod

    hybrid.kernel_consts(hybrid.HybridGeometry())  # hybrid._solve_all
    eta0 = np.radians([[60.0, 60.0, 60.0]])
    tripod.eta(tripod.plate_frame_units(eta0), eta0)  # tripod._eta_all
    from paragym.mechanisms.capaman import DEFAULT_GEOMETRY
    from paragym.sim import capaman_clearance, capaman_grid

    grids = capaman_clearance.DistanceGrids(1)
    capaman_clearance.grid_clearance(np.zeros((1, 3)), grids, capaman_grid.cluster_points(DEFAULT_GEOMETRY,
                                     spacing=0.01))  # capaman_clearance._clearance_one, in _clearance_serial
    print("\\n".join(sorted(set(compiled))))
""")


@pytest.mark.slow
def test_the_kernels_compile_no_shape_checked_slice_copy(tmp_path):
    """An array copied into a slice (``out[:] = e``) makes numba compile a shape check whose error message
    formats tuples: about 4 s of compile per kernel, once per array rank. The kernels copy by element."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    compiled = out.stdout.split()
    assert {"_solve_all", "_eta_all", "_clearance_one"} <= set(compiled), out.stdout  # the check saw them compile
    assert not [name for name in compiled if "raise_with_shape_context" in name], compiled
