"""Pictures in the papers' form, written as PNG with matplotlib's Agg backend.

What every task shares is here (an episode's first frame and rewards, training and imitation curves, the
leaderboard's bars); each task's own pictures are in ``paragym.plots.<task>``."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from paragym.rollout import Episode  # noqa: E402

__all__ = ["plot_episode", "plot_imitation_curve", "plot_leaderboard", "plot_training_curve"]

#: the names of before paragym 0.9 of the tasks' own pictures, answered from their modules with a DeprecationWarning
_MOVED = {"plot_capaman_episode": ("capaman", "plot_episode"), "plot_capaman_motion": ("capaman", "plot_motion"),
          "plot_hybrid_plan": ("hybrid", "plot_plan"), "plot_hybrid_episode": ("hybrid", "plot_episode"),
          "plot_orthoglide_cases": ("orthoglide", "plot_cases"), "plot_kappa_episode": ("orthoglide", "plot_episode"),
          "plot_tripod_estimates": ("tripod", "plot_estimates")}


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        import importlib
        import warnings

        task, new = _MOVED[name]
        warnings.warn(f"paragym.plots.{name} is paragym.plots.{task}.{new} since paragym 0.9", DeprecationWarning,
                      stacklevel=2)
        return getattr(importlib.import_module(f"paragym.plots.{task}"), new)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _save(fig: Any, path: str | Path, title: str, dpi: int = 100,
          rect: tuple[float, float, float, float] = (0, 0, 1, 1)) -> Path:
    """Title, lay out (within ``rect`` of the figure), write the PNG (making its folder), close; the path."""
    fig.suptitle(title, wrap=True)  # a long title breaks into lines rather than running off both edges
    fig.tight_layout(rect=rect)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def plot_episode(ep: Episode, path: str | Path, title: str = "") -> Path:
    """Any task's episode: its first frame (when it has one) and its rewards against the step."""
    frames = [f for f in ep.frames[:1] if f is not None]
    fig, axes = plt.subplots(1, 1 + len(frames), figsize=(4.5 * (1 + len(frames)), 3.6))
    axes = np.atleast_1d(axes)
    if frames:
        axes[0].imshow(frames[0])
        axes[0].set_axis_off()
    ax = axes[-1]
    rewards = np.asarray(ep.rewards, float)
    ax.plot(np.arange(1, len(rewards) + 1), rewards, label="reward")
    ax.plot(np.arange(1, len(rewards) + 1), np.cumsum(rewards), label="return so far")
    ax.set_xlabel("step")
    ax.legend()
    return _save(fig, path, title or f"{len(rewards)} steps, return {rewards.sum():.3f}, success {ep.success}")


def plot_training_curve(curve: dict[str, list], path: str | Path, title: str = "") -> Path:
    """A training run: the return of each training episode (dots, and its
    running mean over 20) and of the periodic evaluations (mean +- std), with
    the evaluations' success rate on the right axis, against env steps."""
    fig, ax = plt.subplots(figsize=(7, 4))
    steps, ret = np.asarray(curve["train_timesteps"], float), np.asarray(curve["train_return"], float)
    if len(ret):
        ax.plot(steps, ret, ".", ms=2, color="0.75", label="training episodes")
        window = min(20, len(ret))
        smooth = np.convolve(ret, np.ones(window) / window, mode="valid")
        ax.plot(steps[window - 1:], smooth, color="0.35", lw=1, label=f"running mean ({window})")
    ev_t = np.asarray(curve["eval_timesteps"], float)
    if len(ev_t):
        mean, std = np.asarray(curve["eval_mean_return"]), np.asarray(curve["eval_std_return"])
        ax.errorbar(ev_t, mean, yerr=std, fmt="o-", color="C0", capsize=3, label="evaluation (mean +- std)")
        rate = [np.nan if r is None else r for r in curve["eval_success_rate"]]
        if not np.all(np.isnan(rate)):
            ax2 = ax.twinx()
            ax2.plot(ev_t, rate, "s--", color="C2", label="evaluation success rate")
            ax2.set_ylim(-0.05, 1.05)
            ax2.set_ylabel("success rate", color="C2")
    ax.set_xlabel("env steps")
    ax.set_ylabel("episode return")
    if len(ret) or len(ev_t):
        ax.legend(loc="lower right", fontsize=8)
    else:  # a run too short to finish an episode or reach an evaluation: say so instead of an empty frame
        ax.text(0.5, 0.5, "no training episode finished and no evaluation yet", ha="center", va="center",
                transform=ax.transAxes, color="0.4")
    return _save(fig, path, title, dpi=90)


def plot_imitation_curve(algo: str, curve: dict[str, list[float]], path: str | Path, title: str = "") -> Path:
    """An imitation run's curve: for ``bc``, the loss per epoch on the training
    and the held-out episodes; for ``dagger``, the success of each round's
    rollouts and of its evaluation against the pairs aggregated."""
    fig, ax = plt.subplots(figsize=(7, 4))
    if algo == "bc":
        ax.plot(curve["epoch"], curve["train_loss"], label="training episodes")
        ax.plot(curve["epoch"], curve["holdout_loss"], label="held-out episodes")
        ax.set_xlabel("epoch")
        ax.set_ylabel("negative log-likelihood of the expert's action (lower is better)")
    else:
        ax.plot(curve["pairs"], curve["rollout_success"], "o-", label="rollouts (iteration 0: the expert)")
        ax.plot(curve["pairs"], curve["eval_success"], "s-", label="evaluation, deterministic policy")
        ax.set_xlabel("state-action pairs aggregated")
        ax.set_ylabel("success rate")
        ax.set_ylim(-0.02, 1.02)
    ax.legend()
    return _save(fig, path, title, dpi=90)


def cut_at_zero(values: np.ndarray, err: np.ndarray) -> tuple[np.ndarray, bool]:
    """Whiskers (2 x n: below, above each of ``values``) whose lower ends stop at 0, and whether any was cut: a
    Student's t interval of a quantity that cannot be negative (an error in cm, kappa) may reach below 0."""
    cut = err[0] > values
    return np.vstack([np.where(cut, values, err[0]), err[1]]), bool(cut.any())


def plot_leaderboard(summaries: Sequence[Any], key: str, label: str, path: str | Path, title: str = "",
                     higher_is_better: bool = False) -> Path:
    """One env's leaderboard as three bar panels, in rank order: success
    rate and mean return with their 95 % intervals (``success_ci``,
    ``return_ci`` of each summary), and the env's primary metric
    (which way is better written on its axis; drawn as dots on an axis that
    starts near the smallest value, and says so, when the values differ by
    little; its intervals cut at 0 when no value is negative). Colours are
    the policy kinds, in a legend."""
    from matplotlib.patches import Patch

    names = [s.policy for s in summaries]
    colours = {"reference": "C3", "paper case": "C1", "other": "C4", "learned": "C0", "floor": "0.6", "user": "C2"}
    col = [colours.get(s.kind, "C2") for s in summaries]
    y = np.arange(len(names))
    def whiskers(values: np.ndarray, cis: list[tuple[float, float]]) -> np.ndarray:
        lo, hi = np.array(cis, float).T
        return np.nan_to_num(np.vstack([values - lo, hi - values]).clip(min=0.0))

    success = np.array([s.success_rate for s in summaries])
    returns = np.array([s.return_mean for s in summaries])
    panels = [("success rate (higher is better)\nbars: 95 % Wilson interval", success,
               whiskers(success, [s.success_ci for s in summaries])),
              ("mean return (higher is better)\nbars: 95 % Student's t interval", returns,
               whiskers(returns, [s.return_ci for s in summaries]))]
    if key != "return":
        primary = np.array([s.metrics.get(key, np.nan) for s in summaries], float)
        panels.append((f"{label} ({'higher' if higher_is_better else 'lower'} is better)\nbars: 95 % Student's t "
                       f"interval", primary, whiskers(primary, [getattr(s, "primary_ci", (np.nan, np.nan))
                                                                for s in summaries])))
    fig, axes = plt.subplots(1, len(panels), figsize=(4 * len(panels), 0.45 * len(names) + 2.0), sharey=True)
    for i, (ax, (name, values, err)) in enumerate(zip(axes, panels, strict=True)):
        finite = values[np.isfinite(values)]
        if i == 2 and len(finite) and finite.min() >= 0:  # a metric that cannot be negative: no interval below 0
            err, cut = cut_at_zero(values, err)
            name += ", cut at 0" if cut else ""
        if i == 2 and len(finite) and finite.min() > 0 and np.ptp(finite) < 0.5 * finite.max():
            # values close together, far from 0: dots on an axis that starts near the smallest, which says so
            for k in range(len(y)):
                ax.errorbar(values[k], y[k], xerr=err[:, k:k + 1], fmt="o", color=col[k], capsize=2)
            name += "\n(dots: the axis does not start at 0)"
        else:
            ax.barh(y, values, xerr=err, color=col, capsize=2)
        ax.set_xlabel(name)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(y, names)
    axes[0].invert_yaxis()
    axes[0].set_xlim(0, 1.05)
    kinds = [k for k in colours if any(s.kind == k for s in summaries)]
    fig.legend(handles=[Patch(color=colours[k], label=k) for k in kinds], loc="lower center", ncol=len(kinds),
               fontsize=8, frameon=False)
    return _save(fig, path, title, dpi=90, rect=(0, 0.5 / (0.45 * len(names) + 2.0), 1, 1))
