"""Which levers of the hybrid's action clear a path that breaks a leg limit midway: the design measurement
behind its ladder (issue 51).

Pairs of poses are drawn from the hybrid's box (v2's and the rungs': the
generator's first filters) until ``--candidates``; kept are those whose ends
are within the limits at the start split 0.5 and whose nominal path (every
fourth sample) breaks one in its middle, as on every rung. For each kept
pair, every constant action of a grid is played on the whole nominal path
(101 samples, eq 14: limits and singularity) under two readings of the
offset lever:

* ``set``, the action as the released ids and rungs read it: the split moves
  ``a_0 * 0.05`` a sample (clipped to [0, 1]), the offset is ``a_1..3 *
  j_bar`` (20 mm) at every sample but the last; the grid is {-1, -0.5, 0,
  0.5, 1}^4;
* ``integrated``: an offset that moves at a bounded rate and must be back at
  zero at the end, so that a constant offset other than zero cannot finish
  (it reaches its bound and stays): the constants left are the split's
  ramps at zero offset, ``a_0`` in 21 steps over [-1, 1].

Printed: the kept pairs, those that no constant clears under each reading,
and, of the latter under ``integrated``, those the reference's split
schedule (:class:`~paragym.planners.polynomial_detour.PolynomialDetourPlanner`
as paper 002 states it: a rate-limited split schedule, detours only where
none works) gets through without a detour, and of those, how many no single split gets
through (the split must go and come back).

    python benchmarks/hybrid_levers.py --candidates 300000
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

from paragym.mechanisms import hybrid
from paragym.planners.base import PlanningError
from paragym.planners.polynomial_detour import PolynomialDetourPlanner
from paragym.tasks.hybrid import POSE_HIGH, POSE_LOW, SPLITS, nominal_rows
from paragym.tasks.hybrid_step import LADDER_RULES, HybridParams

#: the split's rate and the offset's range of the rungs' defaults (the task's parameters)
_DEFAULTS = HybridParams.from_kwargs(LADDER_RULES[0])
MAX_DELTA_STEP, J_BAR = _DEFAULTS.max_delta_step, _DEFAULTS.j_bar


def constants_clear(path: np.ndarray, grid: np.ndarray, g: hybrid.HybridGeometry) -> np.ndarray:
    """Which constant actions (C, 4) keep every sample of ``path`` (K, 6) free (eq 14), the offset set at every
    sample but the last."""
    k = len(path)
    split = np.clip(0.5 + np.arange(k)[None] * grid[:, :1] * MAX_DELTA_STEP, 0.0, 1.0)  # 0.5 at sample 0
    poses = np.repeat(path[None], len(grid), 0)
    poses[:, 1:-1, :3] += grid[:, None, 1:] * J_BAR
    free = hybrid.solve_rows(poses.reshape(-1, 6), split.reshape(-1), g)[4]
    return free.reshape(len(grid), k).all(axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--candidates", type=int, default=300_000, help="pairs drawn from the box")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    g = hybrid.DEFAULT_GEOMETRY
    levels = (-1.0, -0.5, 0.0, 0.5, 1.0)
    set_grid = np.array(list(itertools.product(levels, repeat=4)))
    ramps = np.zeros((21, 4))
    ramps[:, 0] = np.linspace(-1.0, 1.0, 21)
    planner = PolynomialDetourPlanner(g)
    rng = np.random.default_rng(args.seed)
    count = dict(drawn=0, kept=0, set=0, integrated=0, scheduled=0, go_and_return=0)
    t0 = time.perf_counter()
    while count["drawn"] < args.candidates:
        p0, p1 = rng.uniform(POSE_LOW, POSE_HIGH, (4096, 6)), rng.uniform(POSE_LOW, POSE_HIGH, (4096, 6))
        count["drawn"] += 4096
        idx = np.flatnonzero(hybrid.within_limits(p0, 0.5, g) & hybrid.within_limits(p1, 0.5, g))
        middle = nominal_rows(p0[idx], p1[idx], every=4)[:, 1:-1]
        at_half = hybrid.within_limits(middle.reshape(-1, 6), 0.5, g).reshape(len(idx), -1)
        for i in idx[~at_half.all(axis=1)]:
            count["kept"] += 1
            path = nominal_rows(p0[i:i + 1], p1[i:i + 1])[0]
            count["set"] += not constants_clear(path, set_grid, g).any()
            if constants_clear(path, ramps, g).any():
                continue
            count["integrated"] += 1
            try:
                plan = planner.plan(p0[i], p1[i])
            except PlanningError:
                continue
            if np.any(plan.offsets != 0):
                continue
            count["scheduled"] += 1
            inner = path[1:-1]
            through = hybrid.solve_rows(np.repeat(inner, len(SPLITS), 0), np.tile(SPLITS, len(inner)), g)[4]
            count["go_and_return"] += not through.reshape(len(inner), len(SPLITS)).all(axis=0).any()
    print(f"{count['drawn']:,} pairs drawn from the box in {time.perf_counter() - t0:.0f} s (seed {args.seed})")
    print(f"{count['kept']:,} break a leg limit midway at the start split, both ends within the limits")
    print(f"  no constant of the 5^4 grid clears the path, offset set (as released):       {count['set']:,}")
    print(f"  no split ramp clears it, offset integrated and returned (constants at 0):    {count['integrated']:,}")
    print(f"    of these, the reference's split schedule gets through without a detour:    {count['scheduled']:,}")
    print(f"      of these, no single split of 0, 0.1, ..., 1 gets through (go and return): "
          f"{count['go_and_return']:,}")


if __name__ == "__main__":
    main()
