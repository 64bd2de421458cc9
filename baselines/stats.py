"""How sure a number is: the 95 % intervals every table and picture of paragym shows.

* A success rate (k successes in n episodes): Wilson's score interval
  (:func:`wilson`, SciPy's ``binomtest``), which stays inside [0, 1] and is
  not degenerate at 0 or n: 3 of 3 is [0.44, 1.00], 48 of 50 [0.87, 0.99].
* A policy's mean over episodes (a return, a task's metric): Student's t
  interval (:func:`mean_ci`).
* A mean over training runs (the report's learning curves): the percentile
  bootstrap (:func:`bootstrap_mean_ci`), runs resampled, from a fixed seed
  so that a report is the same every time it is written from the same logs.

Two policies are separable on a measure when their intervals do not
overlap (:func:`separable`): a conservative test (two 95 % intervals that
do not overlap differ at well under 5 %), and the one a reader can check
by eye in the table.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BOOTSTRAP_REPS", "CONFIDENCE", "ahead", "bootstrap_mean_ci", "half_width", "mean_ci", "resolvable_drop",
           "separable", "wilson"]

CONFIDENCE = 0.95
BOOTSTRAP_REPS = 2000


def wilson(successes: int, n: int) -> tuple[float, float]:
    """Wilson's 95 % score interval of a success rate of ``successes`` in ``n`` trials ((nan, nan) for none)."""
    from scipy.stats import binomtest

    if n <= 0:
        return (float("nan"), float("nan"))
    ci = binomtest(int(successes), int(n)).proportion_ci(CONFIDENCE, method="wilson")
    return (float(ci.low), float(ci.high))


def bootstrap_mean_ci(values: np.ndarray, rng: np.random.Generator, reps: int = BOOTSTRAP_REPS
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mean over the first axis (runs) of ``values`` (runs, points) and
    the percentile bootstrap's 95 % interval of that mean, runs resampled."""
    values = np.asarray(values, float)
    n = len(values)
    picks = rng.integers(0, n, (reps, n))
    means = values[picks].mean(axis=1)  # (reps, points)
    tail = (1 - CONFIDENCE) / 2 * 100
    return values.mean(axis=0), np.percentile(means, tail, axis=0), np.percentile(means, 100 - tail, axis=0)


def mean_ci(values: list[float] | np.ndarray) -> tuple[float, float]:
    """Student's t 95 % interval of the mean of ``values`` (one per episode):
    mean +- t(0.975, n - 1) s / sqrt(n). Chosen over the bootstrap for the
    leaderboard's means because a table may rest on three episodes, where a
    percentile bootstrap cannot reach beyond the three values and covers the
    mean far less often than it claims; at 50 episodes the two agree.
    (nan, nan) for fewer than two values or non-finite ones; a point for
    equal values."""
    from scipy.stats import t

    x = np.asarray(values, float)
    if len(x) < 2 or not np.all(np.isfinite(x)):
        return (float("nan"), float("nan"))
    half = float(t.ppf(0.5 + CONFIDENCE / 2, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x)))
    return (float(x.mean() - half), float(x.mean() + half))


def separable(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether two intervals do not overlap (False when either is unknown)."""
    if not all(np.isfinite(v) for v in (*a, *b)):
        return False
    return a[1] < b[0] or b[1] < a[0]


def resolvable_drop(successes: int, n: int) -> float | None:
    """The smallest success rate below ``successes`` of ``n`` that the tables can tell apart from it: the least
    d = m / n for which Wilson's interval of ``successes - m`` lies wholly below that of ``successes`` (both of
    ``n`` episodes; :func:`ahead`). None where no rate can be: at 0 successes, or too few episodes (3 of 3 and
    0 of 3 overlap). The noise floor of a leaderboard table on success."""
    top = wilson(successes, n)
    for m in range(1, successes + 1):
        if ahead(top, wilson(successes - m, n), +1):
            return m / n
    return None


def half_width(interval: tuple[float, float]) -> float:
    """Half an interval's width (nan where it is unknown)."""
    lo, hi = interval
    return (hi - lo) / 2 if np.isfinite(lo) and np.isfinite(hi) else float("nan")


def ahead(a: tuple[float, float], b: tuple[float, float], sign: int) -> bool:
    """Whether interval ``a`` lies wholly on the better side of ``b`` (``sign`` +1: higher is better; -1: lower)."""
    if not separable(a, b):
        return False
    return a[0] > b[1] if sign > 0 else a[1] < b[0]
