"""The Orthoglide's pictures (paper 003): kappa along the path for the table strategies, and an episode's."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from paragym.plots import _save
from paragym.rollout import Episode

__all__ = ["plot_cases", "plot_episode"]


def plot_cases(task: Any, cases: Sequence[Any], optimum: np.ndarray, geometry: Any,
                          path: str | Path) -> Path:
    """Paper 003's Figs 5-13 in one picture: for each case, the initial
    configuration with the path on the table and in the fixed frame; the
    joint trajectories; kappa(t) of the three cases with the pointwise best."""
    from paragym.mechanisms import orthoglide as og

    fig, axes = plt.subplots(3, 3, figsize=(15, 13))
    d = geometry.direction
    for col, case in enumerate(cases):
        ax = axes[0, col]
        origin = np.asarray(geometry.table_origin) + case.rho[:, 0:1] * d  # table origin over time
        fixed = task.points + origin
        rho0 = case.rho[0]
        a = np.array([geometry.slider2_origin + rho0[1], 0.0])
        b = np.array([0.0, geometry.slider3_origin + rho0[2]])
        tool = og.forward(rho0[None], geometry)[0] + origin[0]
        ax.plot(*(task.points + origin[0]).T, color="tab:orange", lw=1, label="path on the table (at t = 0)")
        ax.plot(*fixed.T, color="tab:blue", lw=1, label="path in the fixed frame")
        ax.plot([a[0], tool[0], b[0]], [a[1], tool[1], b[1]], "k-o", lw=2, ms=4, label="links at t = 0")
        ax.axhline(0, color="gray", lw=0.5)
        ax.axvline(0, color="gray", lw=0.5)
        ax.set_aspect("equal")
        ax.set_title(f"{case.name}: initial configuration")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        if col == 0:
            ax.legend(fontsize=7, loc="lower right")
        ax = axes[1, col]
        for j, name in enumerate(("rho1 (table)", "rho2", "rho3")):
            ax.plot(case.t, case.rho[:, j], label=name)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("joint [m]")
        ax.set_title("joint trajectories")
        ax.legend(fontsize=7)
        ax = axes[2, col]
        ax.plot(case.t, case.kappa, label=f"{case.name}: mean {case.kappa.mean():.3f}, max {case.kappa.max():.3f}")
        ax.plot(task.t, optimum, "k:", lw=1, label="best reachable at each point")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("kappa(J)")
        ax.set_ylim(1.0, max(2.0, float(np.nanmax(case.kappa)) * 1.05))
        ax.legend(fontsize=7)
    return _save(fig, path, f"2PRR + table, {task.name} task: the paper's cases (a), (b), (c)", dpi=90)


def plot_episode(ep: Episode, path: str | Path) -> Path:
    """One Orthoglide2PRRKappa-v0 episode: the joints and kappa over time."""
    rho = np.array([i["rho"] for i in ep.infos])
    kap = np.array([i["kappa"] for i in ep.infos])
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    for j, name in enumerate(("rho1 (table)", "rho2", "rho3")):
        axes[0].plot(rho[:, j], label=name)
    axes[0].legend(fontsize=8)
    axes[0].set_xlabel("step")
    axes[0].set_ylabel("joint [m]")
    axes[1].plot(kap)
    axes[1].set_xlabel("step")
    axes[1].set_ylabel("kappa(J)")
    title = f"success={ep.infos[-1]['is_success']}, mean kappa {kap.mean():.3f}, max {kap.max():.3f}"
    return _save(fig, path, title)


