"""Which levers of the hybrid's action clear a path that breaks a leg limit midway: the design measurement
behind its ladder.

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

With ``--returning MM`` it measures instead the pairs of the ladder v1's easy rung
(:func:`~paragym.tasks.hybrid.split_ladder_scenarios`: no split ramp gets through at zero offset, a split
schedule does): how many some constant action clears were the offset back, with a range of MM per axis, moving
at most a tenth of it a sample and held within what can still come back to zero by the end (so that a constant
offset rises, rides and returns): 21 split rates x {-1, -0.5, 0, 0.5, 1}^3 offset rates. This is why the ladder
v1 takes the offset away rather than bounding it.

Printed: the kept pairs, those that no constant clears under each reading,
and, of the latter under ``integrated``, those the reference's split
schedule (:class:`~paragym.planners.polynomial_detour.PolynomialDetourPlanner`
as paper 002 states it: a rate-limited split schedule, detours only where
none works) gets through without a detour, and of those, how many no single split gets
through (the split must go and come back).

    python benchmarks/hybrid_levers.py --candidates 300000
    python benchmarks/hybrid_levers.py --returning 2 --pairs 150
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

from paragym.mechanisms import hybrid
from paragym.planners.base import PlanningError
from paragym.planners.polynomial_detour import PolynomialDetourPlanner
from paragym.tasks.hybrid import POSE_HIGH, POSE_LOW, SPLIT_LADDER, SPLITS, nominal_rows, split_ladder_scenarios
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


def returning_clear(path: np.ndarray, grid: np.ndarray, j_bar: float, g: hybrid.HybridGeometry) -> np.ndarray:
    """Which constant actions (C, 4) keep every sample of ``path`` (K, 6) free (eq 14) with the offset moving at
    ``a_1..3 * j_bar / 10`` a sample, held within ``min(j_bar, (K - 1 - k) j_bar / 10)`` at sample k (so that it
    is back at zero at the end)."""
    k = np.arange(len(path))
    split = np.zeros((len(grid), len(path)))
    delta = np.full(len(grid), 0.5)
    for i in range(1, len(path)):  # the split as the step moves it, a clipped sum
        delta = np.clip(delta + grid[:, 0] * MAX_DELTA_STEP, 0.0, 1.0)
        split[:, i] = delta
    split[:, 0] = 0.5
    room = np.minimum(1.0, 0.1 * (len(path) - 1 - k))[None, :, None]
    offset = np.clip(k[None, :, None] * grid[:, None, 1:] * 0.1, -room, room) * j_bar
    poses = np.repeat(path[None], len(grid), 0)
    poses[:, :, :3] += offset
    free = hybrid.solve_rows(poses.reshape(-1, 6), split.reshape(-1), g)[4]
    return free.reshape(len(grid), len(path)).all(axis=1)


def returning(j_bar_mm: float, pairs: int, seed: int) -> None:
    """The ``--returning`` measurement (module docstring)."""
    g = hybrid.DEFAULT_GEOMETRY
    levels = (-1.0, -0.5, 0.0, 0.5, 1.0)
    grid = np.array([(c, *o) for c in np.linspace(-1.0, 1.0, 21) for o in itertools.product(levels, repeat=3)])
    t0 = time.perf_counter()
    drawn = split_ladder_scenarios([np.random.default_rng([seed, i]) for i in range(pairs)], SPLIT_LADDER[0], g)
    cleared = sum(bool(returning_clear(nominal_rows(np.array([d.p0]), np.array([d.p1]))[0], grid, j_bar_mm / 1000,
                                       g).any()) for d in drawn)
    print(f"{pairs} pairs of the ladder v1's easy rung (seed {seed}), {len(grid):,} constants, offset back at the end "
          f"within {j_bar_mm:g} mm: {cleared} cleared by some constant ({time.perf_counter() - t0:.0f} s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--candidates", type=int, default=300_000, help="pairs drawn from the box")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--returning", type=float, default=None, metavar="MM",
                        help="measure the ladder v1's easy rung under a returning offset of this range (mm)")
    parser.add_argument("--pairs", type=int, default=150, help="with --returning: pairs of the rung")
    args = parser.parse_args()
    if args.returning is not None:
        returning(args.returning, args.pairs, args.seed)
        return
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
