"""The hybrid's scenarios (paper 002): start and goal poses, the paper's case, random pairs and their checks.

Used by the env, the vector env, the planner and the CLI alike: a pair is
drawn and validated here once.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from types import SimpleNamespace
from typing import Any

import numpy as np
from numba import njit

from paragym.kernels import entry
from paragym.mechanisms import hybrid
from paragym.tasks import base
from paragym.trajectories import nominal_path
from paragym.units import MM

__all__ = ["LADDER", "POSE_HIGH", "POSE_LOW", "SCENARIOS", "SPLIT_LADDER", "SPLIT_LADDER_V2", "HybridRung",
           "HybridScenario", "SplitRung", "draw_scenarios", "knob_table", "ladder_scenarios", "lookahead_split",
           "nominal_rows", "paper_scenario", "random_scenario", "random_scenarios", "resolve_scenario", "split_args",
           "split_knob_table", "split_ladder_scenarios", "validate_scenario"]

SCENARIOS = ("paper", "random")


@dataclass(frozen=True)
class HybridScenario:
    """Start and goal of the end-effector, as displacements from home (m, rad)."""

    name: str
    p0: tuple[float, ...]
    p1: tuple[float, ...]
    geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY
    seed: int | None = None


def paper_scenario(geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY) -> HybridScenario:
    """Paper 002's example: P0 = [10, 10, 10, 0, 0, 0], P1 = [100, 80, 110, 0.15, 0.25, 0] (mm, rad)."""
    p0 = (10 * MM, 10 * MM, 10 * MM, 0.0, 0.0, 0.0)
    p1 = (100 * MM, 80 * MM, 110 * MM, 0.15, 0.25, 0.0)
    return HybridScenario("paper", p0, p1, geometry)


SPLITS = np.linspace(0, 1, 11)  # the splits Delta the scenario checks try (0.5 among them, exactly)
#: the box both end poses of a random pair are drawn from, v2's and the rungs' alike (E's displacement from home:
#: m, m, m, rad, rad, rad), read-only
POSE_LOW = np.array([-0.10, -0.10, 0.0, -0.3, -0.3, -0.4])
POSE_HIGH = np.array([0.10, 0.10, 0.12, 0.3, 0.3, 0.4])
POSE_LOW.setflags(write=False)
POSE_HIGH.setflags(write=False)


def _some_split(p: np.ndarray, test: Any, passed: np.ndarray | None = None, at_once: int = 4096) -> np.ndarray:
    """Whether ``test(poses, splits)`` holds at some split of :data:`SPLITS`
    for each pose (M, 6) (``passed``: those known to pass at 0.5). Up to
    ``at_once`` evaluations, every split in one call (a single env's reset);
    beyond, the splits are tried from 0.5 outwards, each only on the poses no
    split has passed yet: the same answer for a fraction of the work."""
    ok = np.zeros(len(p), bool) if passed is None else passed.copy()
    todo = np.flatnonzero(~ok)
    if len(todo) * len(SPLITS) <= at_once:
        hit = test(np.repeat(p[todo], len(SPLITS), 0), np.tile(SPLITS, len(todo)))
        ok[todo] = hit.reshape(len(todo), len(SPLITS)).any(axis=1)
        return ok
    for d in SPLITS[np.argsort(np.abs(SPLITS - 0.5), kind="stable")]:
        if not todo.size:
            break
        if passed is not None and d == 0.5:
            continue
        hit = test(p[todo], np.full(len(todo), d))
        ok[todo[hit]] = True
        todo = todo[~hit]
    return ok


def _candidates_pass(p0: np.ndarray, p1: np.ndarray, hard: np.ndarray, geometry: hybrid.HybridGeometry,
                     chunk: int = 256) -> np.ndarray:
    """Which candidate pairs (C, 6) + (C, 6) pass the checks of
    :func:`random_scenarios` after the screen (``hard`` (C,): must
    the nominal path at Delta = 0.5 fail on its every fourth sample). The
    checks run stage by stage on the survivors, ``chunk`` pairs at a time."""
    def limits(p: np.ndarray, d: np.ndarray) -> np.ndarray:
        return hybrid.within_limits(p, d, geometry)

    def free(p: np.ndarray, d: np.ndarray) -> np.ndarray:
        return hybrid.solve_rows(p, d, geometry)[4]

    out = np.zeros(len(p0), bool)
    for lo in range(0, len(p0), chunk):
        a, b, h = p0[lo:lo + chunk], p1[lo:lo + chunk], hard[lo:lo + chunk]
        nominal = nominal_rows(a, b, every=4)  # every fourth sample of the nominal path: (c, 26, 6)
        m = nominal.shape[1]
        at_half = limits(nominal.reshape(-1, 6), np.full(len(a) * m, 0.5)).reshape(-1, m)
        # a failure found on these samples is a real one; none found: not hard enough
        idx = np.flatnonzero(~(h & at_half.all(axis=1)))
        # some split keeps the legs within limits at each sample (necessary for a plan) ...
        table = _some_split(nominal[idx].reshape(-1, 6), limits, at_half[idx].ravel()).reshape(len(idx), m)
        idx = idx[table.all(axis=1)]
        # ... and eq 14 in full holds at P0 (Delta = 0.5) and at P1 for some split
        idx = idx[free(a[idx], np.full(len(idx), 0.5))]
        out[lo + idx[_some_split(b[idx], free)]] = True
    return out


def random_scenarios(rngs: list[np.random.Generator],
                     geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, hard_share: float = 0.5,
                     max_tries: int = 2000) -> list[HybridScenario]:
    """One seeded pair of poses per generator: P0 singularity-free within
    limits at the starting split Delta = 0.5, P1 at some Delta; x, y in
    +-100 mm, z in 0-120 mm, roll and pitch in +-0.3 rad, yaw in +-0.4 rad.
    With probability ``hard_share`` the pair is drawn again until its nominal
    path at Delta = 0.5 meets a singularity or a leg limit (of unbiased pairs
    about a quarter do), so that doing nothing does not solve the env. At
    every fourth pose of the nominal path some split must keep the legs within
    limits, and P0 and P1 must pass eq 14 in full (necessary conditions for a
    plan, cheap enough for every reset; the tests measure how often the
    planner then succeeds: every time on 60 seeds).

    Each generator draws what it would alone (whether hard, then candidate
    pairs 16 at a time, the first that passes taken); the candidates of all
    generators are screened and checked together."""
    low, high = POSE_LOW, POSE_HIGH
    batch = 16
    hard = np.array([rng.random() < hard_share for rng in rngs], bool)
    out: list[HybridScenario | None] = [None] * len(rngs)
    pending = np.arange(len(rngs))
    for _ in range(max(1, max_tries // batch)):
        if not pending.size:
            break
        draws = [(rngs[i].uniform(low, high, (batch, 6)), rngs[i].uniform(low, high, (batch, 6))) for i in pending]
        p0 = np.array([d[0] for d in draws]).reshape(-1, 6)
        p1 = np.array([d[1] for d in draws]).reshape(-1, 6)
        # screen every candidate with the leg limits alone (cheap), then check the survivors fully
        screened = hybrid.within_limits(p0, 0.5, geometry)
        screened[screened] = _some_split(p1[screened], lambda p, d: hybrid.within_limits(p, d, geometry))
        screened = screened.reshape(len(pending), batch)
        # the screened candidates in each generator's order: the first of every generator, then the
        # second of those not yet served, ... (as one generator alone tries them, one by one)
        order = np.argsort(~screened, axis=1, kind="stable")
        waiting = np.arange(len(pending))
        for rank in range(batch):
            waiting = waiting[screened[waiting, order[waiting, rank]]]
            if not waiting.size:
                break
            k = waiting * batch + order[waiting, rank]
            good = _candidates_pass(p0[k], p1[k], hard[pending[waiting]], geometry)
            for r, kk in zip(waiting[good], k[good], strict=True):
                out[pending[r]] = HybridScenario("random", tuple(map(float, p0[kk])), tuple(map(float, p1[kk])),
                                                 geometry)
            waiting = waiting[~good]
        pending = np.array([i for i in pending if out[i] is None], np.int64)
    if pending.size:
        raise RuntimeError(f"no reachable pair of poses in {max_tries} tries")
    return out  # type: ignore[return-value]


def random_scenario(rng: np.random.Generator, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY,
                    hard_share: float = 0.5, max_tries: int = 2000) -> HybridScenario:
    """:func:`random_scenarios` for one generator."""
    return random_scenarios([rng], geometry, hard_share, max_tries)[0]


@dataclass(frozen=True)
class HybridRung:
    """The knobs of one rung of the hybrid's difficulty ladder (:func:`ladder_scenarios`).

    Attributes:
        most_splits: at the path's hardest sample, at most this many of the 11 splits 0, 0.1, ..., 1 keep the
            legs within their limits: the fewer, the narrower the way through.
    """

    most_splits: int


#: the hybrid's difficulty ladder, easiest first: on every rung both end poses are within the limits at the
#: starting split 0.5 and the nominal path there breaks a leg limit in its middle, so that neither doing nothing
#: nor stepping the split toward the end pose's need (the greedy floor) succeeds; a rung narrows the splits
#: that get through. (Where P1 itself needs another split, the greedy floor succeeded in 24 of 30: the split it
#: moves for the end also clears the middle.)
LADDER = (HybridRung(most_splits=11), HybridRung(most_splits=3), HybridRung(most_splits=2))


def knob_table(indent: str = "") -> str:
    """The knobs of every rung of :data:`LADDER` as a reStructuredText table (the rung pages show it)."""
    return base.knob_table(LADDER, {"most_splits": "splits through the hardest sample, at most"}, indent)


@dataclass(frozen=True)
class SplitRung:
    """The knobs of one rung of the hybrid's ladder v1 (:func:`split_ladder_scenarios`), where the split Delta is
    the action's only lever.

    Attributes:
        lookahead: the horizons H (samples) of the lookahead rule (:func:`lookahead_split`) that must fail on
            the rung's pairs: the longer, the further ahead the split must be planned.
        margin: how far (m) inside their limits the certificate's schedule keeps every stroke (0 on the ladder
            v1: at the limits; the reference then plans at them and a force-limited actuator overshoots them).
    """

    lookahead: tuple[int, ...]
    margin: float = 0.0


#: the hybrid's ladder v1, easiest first. On every rung the split is the only lever (E stays on its nominal
#: path), both end poses are within the limits at the start split 0.5 and the nominal path there breaks a leg
#: limit midway (as on the ladder v0); no constant rate of the split keeps the path free (eq 14), so the split
#: must be scheduled; a schedule within the rate limit exists on the reference's grid (the rung's certificate:
#: the reference plans it); and the lookahead rule fails at each of the rung's horizons.
SPLIT_LADDER = (SplitRung(()), SplitRung((1,)), SplitRung((1, 5)))
#: the hybrid's ladder v2: the ladder v1's rungs whose certificate keeps every stroke 1 mm inside its limits, the
#: margin the reference plans with (a pair whose only schedules touch a limit is drawn again); the constant rates
#: and the lookahead rule must still fail at the limits themselves
SPLIT_LADDER_V2 = tuple(SplitRung(r.lookahead, margin=0.001) for r in SPLIT_LADDER)
#: the constant split rates a pair of the ladder v1 must defeat (the action's units; float32, as the env
#: receives them): -1, -0.9, ..., 1
SPLIT_RATES = np.linspace(-1.0, 1.0, 21).astype(np.float32).astype(np.float64)
SPLIT_RATES.setflags(write=False)
#: the splits of the ladder v1's certificate: every fifth of the reference's 101 (0, 0.05, ..., 1), one step
#: of the rate limit apart, Delta0 = 0.5 among them
CERTIFICATE_SPLITS = np.linspace(0.0, 1.0, 101)[::5].copy()
CERTIFICATE_SPLITS.setflags(write=False)
_BLOCK = 256  # candidates a compiled draw makes uniforms for at once


def split_knob_table(indent: str = "", ladder: tuple[SplitRung, ...] = SPLIT_LADDER) -> str:
    """The knobs of every rung of ``ladder`` (:data:`SPLIT_LADDER` or :data:`SPLIT_LADDER_V2`) as a
    reStructuredText table (the rung pages show it); the certificate's margin where a rung has one."""
    columns = {"lookahead": "horizons (samples) at which the lookahead rule fails"}
    if any(r.margin for r in ladder):
        columns["margin"] = "certificate's margin inside the stroke limits (mm)"
    shown = tuple(SimpleNamespace(lookahead=", ".join(map(str, r.lookahead)) or "none", margin=f"{r.margin * 1000:g}")
                  for r in ladder)
    return base.knob_table(shown, columns, indent)


@njit(cache=True, error_model="numpy")
def _margin(pose, delta, consts, limits, lengths, work):
    """Eq 14 at one pose (6,) and split: its margin, the least of the strokes' distance inside their limits (in
    half stroke ranges) and of both measures above the threshold, and whether eq 14 holds (the step's test,
    exactly). ``limits``: L_min, L_max (m), the singularity threshold."""
    base_, plat, top, axes, tri_base, pinv_t, home, sc = consts
    l_min, l_max, thr = limits
    mu_h, mu_t = hybrid.k_solve(pose, delta, base_, plat, top, axes, tri_base, pinv_t, home, sc, hybrid.MEASURES,
                                lengths, work)
    half, mid = 0.5 * (l_max - l_min), 0.5 * (l_max + l_min)
    margin, within = min(mu_h - thr, mu_t - thr), True
    for c in range(9):
        within = within and l_min <= lengths[c] <= l_max
        margin = min(margin, 1.0 - abs(lengths[c] - mid) / half)
    return margin, within and mu_h >= thr and mu_t >= thr


@njit(cache=True, error_model="numpy")
def _within(pose, delta, consts, limits, lengths, work):
    """Whether the nine legs are within their limits at one pose (6,) and split (eq 13: the legs alone)."""
    base_, plat, top, axes, tri_base, pinv_t, home, sc = consts
    hybrid.k_solve(pose, delta, base_, plat, top, axes, tri_base, pinv_t, home, sc, hybrid.LEGS_ONLY, lengths, work)
    for c in range(9):
        if not limits[0] <= lengths[c] <= limits[1]:
            return False
    return True


@njit(cache=True, error_model="numpy")
def _free(pose, delta, consts, limits, lengths, work):
    """Whether eq 14 holds at one pose (6,) and split, as :func:`_margin` decides it, the legs solved first and
    the measures only where the legs are within their limits."""
    return _within(pose, delta, consts, limits, lengths, work) and _margin(pose, delta, consts, limits, lengths,
                                                                          work)[1]


@njit(cache=True, error_model="numpy")
def lookahead_split(path, k, delta, horizon, step, consts, limits, lengths, work):
    """The lookahead rule's split rate at sample ``k`` of ``path`` (K, 6) with the split at ``delta``: of 0, -1
    and +1 (ties in that order), the rate whose split, moved by ``rate * step`` a sample (clipped to [0, 1], as
    the step moves it), keeps the worst :func:`_margin` of samples k+1 ... k+``horizon`` the highest. A model's
    one-line rule: it sees ``horizon`` samples ahead and plans nothing."""
    last = path.shape[0] - 1
    best, choice = -math.inf, 0.0
    for rate in (0.0, -1.0, 1.0):
        worst, d = math.inf, delta
        for h in range(1, horizon + 1):
            d = min(1.0, max(0.0, d + rate * step))
            worst = min(worst, _margin(path[min(k + h, last)], d, consts, limits, lengths, work)[0])
        if worst > best:
            best, choice = worst, rate
    return choice


@njit(cache=True, error_model="numpy")
def _plays_free(path, horizon, step, consts, limits, lengths, work):
    """Whether :func:`lookahead_split` at ``horizon`` keeps every sample of ``path`` free from Delta = 0.5, the
    split moved as the step moves it."""
    d = 0.5
    for k in range(path.shape[0] - 1):
        d = min(1.0, max(0.0, d + lookahead_split(path, k, d, horizon, step, consts, limits, lengths, work) * step))
        if not _free(path[k + 1], d, consts, limits, lengths, work):
            return False
    return True


@njit(cache=True, error_model="numpy")
def _ramp_free(path, rate, step, consts, limits, lengths, work):
    """Whether the constant split ``rate`` keeps every sample of ``path`` free from Delta = 0.5, the split moved as
    the step moves it: the legs along the whole ramp first (where a ramp fails, it mostly fails there), then eq
    14 in full."""
    for full in (False, True):
        d = 0.5
        for k in range(path.shape[0] - 1):
            d = min(1.0, max(0.0, d + rate * step))
            ok = _free(path[k + 1], d, consts, limits, lengths, work) if full else \
                _within(path[k + 1], d, consts, limits, lengths, work)
            if not ok:
                return False
    return True


@njit(cache=True, error_model="numpy")
def _scheduled(path, splits, consts, limits, lengths, work):
    """Whether a split schedule on ``splits`` (D,) from Delta = 0.5, at most one grid step a sample, keeps every
    sample of ``path`` free: a depth-first search (the split held, else raised, else lowered) that remembers the
    cells (sample, split) from which no schedule reaches the end, so that each is solved at most once."""
    n, last = splits.shape[0], path.shape[0] - 1
    dead = np.zeros((path.shape[0], n), np.bool_)
    split, tried = np.empty(path.shape[0], np.int64), np.zeros(path.shape[0], np.int64)
    split[0] = np.argmin(np.abs(splits - 0.5))
    if not _free(path[0], splits[split[0]], consts, limits, lengths, work):
        return False
    k = 0
    while k >= 0:
        if k == last:
            return True
        if tried[k] == 3:  # every move from here is dead: so is this cell
            dead[k, split[k]] = True
            k -= 1
            continue
        j = split[k] + (0 if tried[k] == 0 else 1 if tried[k] == 1 else -1)
        tried[k] += 1
        if j < 0 or j >= n or dead[k + 1, j]:
            continue
        if not _free(path[k + 1], splits[j], consts, limits, lengths, work):
            dead[k + 1, j] = True
            continue
        k += 1
        split[k], tried[k] = j, 0
    return False


@njit(cache=True, error_model="numpy")
def _split_pair(p0, p1, shape, lookahead, step, consts, limits, certified, lengths, work, path):
    """Whether the pair (P0, P1) is a pair of the ladder v1's rung (:data:`SPLIT_LADDER`'s module comment):
    ``shape`` s(u) at the samples, ``lookahead`` the rung's horizons, ``certified`` the limits the certificate's
    schedule keeps (``limits`` moved in by the rung's margin); ``path`` (K, 6) receives the nominal path."""
    if not (_within(p0, 0.5, consts, limits, lengths, work) and _within(p1, 0.5, consts, limits, lengths, work)):
        return False  # both ends within the limits at 0.5 (legs alone: cheap)
    breaks = False
    for k in range(shape.shape[0]):
        for c in range(6):
            path[k, c] = p0[c] + (p1[c] - p0[c]) * shape[k]
        if k % 4 == 0 and 0 < k < shape.shape[0] - 1 and not breaks:  # midway at 0.5, every fourth sample
            breaks = not _within(path[k], 0.5, consts, limits, lengths, work)
    if not breaks:
        return False
    for rate in SPLIT_RATES:
        if _ramp_free(path, rate, step, consts, limits, lengths, work):
            return False
    if not _scheduled(path, CERTIFICATE_SPLITS, consts, certified, lengths, work):
        return False
    for h in lookahead:
        if _plays_free(path, h, step, consts, limits, lengths, work):
            return False
    return True


@njit(cache=True, error_model="numpy")
def _split_draw(rng, max_blocks, low, high, shape, lookahead, step, consts, limits, certified, pair):
    """One generator's pair of the rung: blocks of :data:`_BLOCK` candidates of uniforms drawn from ``rng`` (a
    ``numpy.random.Generator``: numba draws numpy's own stream), P0 then P1 of each candidate in ``low`` +
    (``high`` - ``low``) u, until :func:`_split_pair` keeps one (into ``pair`` (2, 6)), at most ``max_blocks``;
    whether it did."""
    lengths, work, path = np.empty(9), np.empty((5, 6, 6)), np.empty((shape.shape[0], 6))
    p0, p1 = np.empty(6), np.empty(6)
    for _ in range(max_blocks):
        u = rng.random((_BLOCK, 12))
        for i in range(_BLOCK):
            for c in range(6):
                p0[c] = low[c] + (high[c] - low[c]) * u[i, c]
                p1[c] = low[c] + (high[c] - low[c]) * u[i, 6 + c]
            if _split_pair(p0, p1, shape, lookahead, step, consts, limits, certified, lengths, work, path):
                for c in range(6):  # by element: a row copied whole compiles numba's shape check (seconds)
                    pair[0, c], pair[1, c] = p0[c], p1[c]
                return True
    return False


#: :func:`_split_draw`'s compiled entry per kind of bit generator (the only type of its call that varies)
_SPLIT_DRAWS: dict[tuple[Any, ...], Any] = {}
#: the last :data:`_SPLIT_MEMO_SIZE` draws of this process: (rung, geometry, path step, rate limit, blocks, the
#: generator's state before) -> (the pair, the generator's state after), oldest first
_SPLIT_MEMO: OrderedDict[tuple[Any, ...], tuple[np.ndarray, Mapping[str, Any]]] = OrderedDict()
_SPLIT_MEMO_SIZE = 4096


@lru_cache(maxsize=16)
def split_args(geometry: hybrid.HybridGeometry, tau: float = 0.01) -> tuple[np.ndarray, Any, np.ndarray]:
    """The path's shape s(u), the geometry's kernel constants and the limits (L_min, L_max, the singularity
    threshold) that :func:`_split_draw` and :func:`lookahead_split` take, made once per geometry and path step (a
    reset must not rebuild them)."""
    g = geometry
    return (np.ascontiguousarray(_path_shape(tau)), hybrid.kernel_consts(g),
            np.array([g.l_min, g.l_max, g.singularity_threshold]))


def split_ladder_scenarios(rngs: list[np.random.Generator], rung: SplitRung,
                           geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, max_delta_step: float = 0.05,
                           tau: float = 0.01, max_blocks: int = 20_000) -> list[HybridScenario]:
    """One pair of poses of a rung of the ladder v1 per generator (named "random" on the rung's env id): blocks of
    candidates from v2's box (:data:`POSE_LOW`, :data:`POSE_HIGH`), the first that passes taken, in one compiled
    call per generator (:func:`_split_draw`). A pair passes when both ends are within the limits at Delta = 0.5
    and the nominal path there breaks a limit midway (every fourth sample); no constant split rate of
    :data:`SPLIT_RATES` keeps every sample of the nominal path free (eq 14); a schedule on
    :data:`CERTIFICATE_SPLITS` from 0.5, one ``max_delta_step`` a sample at most, does with every stroke the
    rung's ``margin`` inside its limits (so the reference's
    serial optimisation, on a grid that holds these splits, finds one); and :func:`lookahead_split` fails at
    each of the rung's horizons."""
    shape, consts, limits = split_args(geometry, tau)
    lookahead = np.array(rung.lookahead, np.int64)
    certified = limits + np.array([rung.margin, -rung.margin, 0.0])
    out = []
    for rng in rngs:
        # a draw is a function of the generator's state: the same state (the same reset seed, as every policy of a
        # leaderboard meets) takes the pair and the state after it from the memo instead of drawing again
        memo_key = (rung, geometry, tau, float(max_delta_step), max_blocks, repr(rng.bit_generator.state))
        if memo_key in _SPLIT_MEMO:
            pair, after = _SPLIT_MEMO[memo_key]
            _SPLIT_MEMO.move_to_end(memo_key)
            rng.bit_generator.state = after
        else:
            pair = np.empty((2, 6))
            call = (rng, max_blocks, POSE_LOW, POSE_HIGH, shape, lookahead, float(max_delta_step), consts, limits,
                    certified, pair)
            key = (type(rng.bit_generator),)
            draw = _SPLIT_DRAWS.get(key) or _SPLIT_DRAWS.setdefault(key, entry(_split_draw, call))  # typed once
            if not draw(*call):
                raise RuntimeError(f"no pair of poses of the rung in {max_blocks * _BLOCK} candidates")
            _SPLIT_MEMO[memo_key] = (pair, rng.bit_generator.state)
            if len(_SPLIT_MEMO) > _SPLIT_MEMO_SIZE:
                _SPLIT_MEMO.popitem(last=False)
        out.append(HybridScenario("random", tuple(map(float, pair[0])), tuple(map(float, pair[1])), geometry))
    return out


def ladder_scenarios(rngs: list[np.random.Generator], rung: HybridRung,
                     geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY,
                     max_tries: int = 200_000) -> list[HybridScenario]:
    """One pair of poses of a rung per generator (named "random" on the rung's env id): candidates drawn 64 at a
    time from each generator, as :func:`random_scenarios` draws them (the same box), the first that passes
    taken. A pair passes when P0 and P1 are within the limits at Delta = 0.5; the nominal path (every fourth
    sample) at 0.5 breaks a limit at some sample strictly between its ends; at every such sample some split of
    :data:`SPLITS` keeps the legs within limits, at the hardest at most ``most_splits`` of the 11; and eq 14
    holds in full at P0 (0.5) and at P1 (some split)."""
    low, high = POSE_LOW, POSE_HIGH
    batch, g = 64, geometry
    out: list[HybridScenario | None] = [None] * len(rngs)
    for i, rng in enumerate(rngs):
        for _ in range(max(1, max_tries // batch)):
            p0, p1 = rng.uniform(low, high, (batch, 6)), rng.uniform(low, high, (batch, 6))
            ok = hybrid.within_limits(p0, 0.5, g)
            ok[ok] = hybrid.within_limits(p1[ok], 0.5, g)
            idx = np.flatnonzero(ok)
            if not idx.size:
                continue
            nominal = nominal_rows(p0[idx], p1[idx], every=4)[:, 1:-1]  # the middle samples
            m = nominal.shape[1]
            at_half = hybrid.within_limits(nominal.reshape(-1, 6), 0.5, g).reshape(-1, m)
            keep = ~at_half.all(axis=1)
            idx, nominal, failing = idx[keep], nominal[keep], ~at_half[keep]
            if not idx.size:
                continue
            flat = nominal[failing]  # the samples that break a limit at 0.5: how many splits keep each within
            counts = hybrid.within_limits(np.repeat(flat, len(SPLITS), 0), np.tile(SPLITS, len(flat)), g)
            fewest = np.full(len(idx), len(SPLITS))
            np.minimum.at(fewest, np.nonzero(failing)[0], counts.reshape(len(flat), len(SPLITS)).sum(axis=1))
            keep = (fewest >= 1) & (fewest <= rung.most_splits)
            for k in idx[keep]:
                a, b = p0[k:k + 1], p1[k:k + 1]
                if hybrid.solve_rows(a, np.full(1, 0.5), g)[4][0] and _some_split(b, lambda p, d: hybrid.solve_rows(
                        p, d, g)[4])[0]:
                    out[i] = HybridScenario("random", tuple(map(float, a[0])), tuple(map(float, b[0])), geometry)
                    break
            if out[i] is not None:
                break
        if out[i] is None:
            raise RuntimeError(f"no pair of poses of the rung in {max_tries} tries")
    return out  # type: ignore[return-value]


@lru_cache(maxsize=4)
def _path_shape(tau: float = 0.01) -> np.ndarray:
    """s(u) of the nominal path at its samples (``nominal_path(0, 1, tau)``), read-only."""
    s = nominal_path(np.zeros(1), np.ones(1), tau)[1][:, 0]
    s.setflags(write=False)
    return s


def nominal_rows(p0: np.ndarray, p1: np.ndarray, tau: float = 0.01, every: int = 1) -> np.ndarray:
    """:func:`nominal_path` for pairs (M, 6) at once, every ``every``-th sample: (M, K, 6)."""
    s = _path_shape(tau)[::every]
    return p0[:, None] + (p1 - p0)[:, None] * s[None, :, None]


def validate_scenario(choice: HybridScenario) -> None:
    """A custom pair that can run: finite poses with angles within +-pi/2, a
    start in the workspace at Delta = 0.5 and a goal that some split Delta
    reaches singularity-free within the leg limits."""
    try:
        p0 = hybrid.check_pose(np.array(choice.p0, dtype=float), "scenario.p0")
        p1 = hybrid.check_pose(np.array(choice.p1, dtype=float), "scenario.p1")
    except (TypeError, ValueError) as exc:
        raise ValueError(str(exc)) from None
    if not hybrid.solve(p0, 0.5, choice.geometry).free[0]:
        raise ValueError("scenario.p0 is outside the workspace: at Delta = 0.5 a leg is out of "
                         "[226.11, 326.11] mm or a stage is singular")
    splits = np.linspace(0, 1, 21)
    if not hybrid.solve(np.repeat(p1, 21, 0), splits, choice.geometry).free.any():
        raise ValueError("scenario.p1 is outside the workspace: no split Delta keeps it singularity-free "
                         "within the leg limits")


def resolve_scenario(choice: Any) -> str | HybridScenario:
    """The scenario argument, checked (:func:`paragym.tasks.base.resolve_scenario`):
    "paper", "random", or a :class:`HybridScenario` that can run."""
    return base.resolve_scenario(choice, SCENARIOS, HybridScenario, validate_scenario)


def draw_scenarios(choice: Any, rngs: list[np.random.Generator],
                   geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY,
                   rung: HybridRung | SplitRung | None = None, max_delta_step: float = 0.05, tau: float = 0.01
                   ) -> list[HybridScenario]:
    """One episode's scenario per generator (single env, vector env and CLI
    alike): the paper's, random pairs drawn from the generators, or the
    custom one once :func:`resolve_scenario` accepts it. On a rung of a ladder (``rung``, of :data:`LADDER`
    or :data:`SPLIT_LADDER`) "random" is the rung's pair (:func:`ladder_scenarios`,
    :func:`split_ladder_scenarios` with the split's rate and the path's step)."""
    choice = resolve_scenario(choice)
    if choice == "random" and rung is not None:
        if isinstance(rung, SplitRung):
            return split_ladder_scenarios(rngs, rung, geometry, max_delta_step, tau)
        return ladder_scenarios(rngs, rung, geometry)
    if choice == "random":
        return random_scenarios(rngs, geometry)
    return [paper_scenario(geometry) if choice == "paper" else choice] * len(rngs)

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = base.renamed(__name__, {
    "resolve_hybrid": "resolve_scenario",
    "hybrid_paper_scenario": "paper_scenario",
    "hybrid_random_scenario": "random_scenario",
    "hybrid_random_scenarios": "random_scenarios",
})
