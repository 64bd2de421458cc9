"""The hybrid's pictures (paper 002): a plan's strokes, split and singularity measures, and an episode's."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from paragym.plots import _save
from paragym.rollout import Episode

__all__ = ["plot_episode", "plot_plan"]


def plot_plan(plan: Any, path: str | Path, title: str = "", l_min: float = 0.22611,
                     l_max: float = 0.32611, threshold: float = 0.2) -> Path:
    """Paper 002's figures for one plan: the motion of platform A and of E in
    x, y, z (Figs 3-8; nominal dashed), the nine leg strokes with the limits,
    the split Delta(u), and the two singularity measures with their threshold."""
    u = plan.u
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    base_e = plan.e_pose - plan.path  # E's home pose, per sample
    for j, name in enumerate("xyz"):
        ax = axes[0, j]
        ax.plot(u, plan.a_pose[:, j] * 1000, color="tab:blue", label="platform A (planned)")
        ax.plot(u, plan.e_pose[:, j] * 1000, color="tab:orange", label="platform E (planned)")
        ax.plot(u, (plan.nominal[:, j] + base_e[:, j]) * 1000, "k--", lw=0.8, label="E nominal")
        ax.set_xlabel("u")
        ax.set_ylabel(f"{name} [mm]")
        ax.set_title(f"motion of A and E in {name}")
    axes[0, 0].legend(fontsize=8)
    ax = axes[1, 0]
    for i in range(9):
        ax.plot(u, plan.lengths[:, i] * 1000, color="tab:gray" if i < 6 else "tab:red", lw=1)
    ax.axhline(l_min * 1000, ls=":", color="k")
    ax.axhline(l_max * 1000, ls=":", color="k")
    ax.set_xlabel("u")
    ax.set_ylabel("leg length [mm]")
    ax.set_title("strokes (grey: hexapod, red: tripod; dotted: limits)")
    ax = axes[1, 1]
    ax.plot(u, plan.delta, color="tab:green")
    for m, c in ((1, "tab:blue"), (2, "tab:red")):
        sel = plan.method == m
        if sel.any():
            ax.scatter(u[sel], plan.delta[sel], s=8, color=c, label={1: "serial", 2: "detour"}[m])
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel("u")
    ax.set_ylabel("Delta")
    ax.legend(fontsize=8)
    ax.set_title("split factor Delta(u)")
    ax = axes[1, 2]
    ax.plot(u, plan.mu_hexapod, label="hexapod")
    ax.plot(u, plan.mu_tripod, label="tripod")
    ax.axhline(threshold, ls=":", color="k", label="threshold")
    ax.set_ylim(0, max(1.2, float(plan.mu_tripod.max()) + 0.1))
    ax.set_xlabel("u")
    ax.set_ylabel("sigma_min / home")
    ax.legend(fontsize=8)
    ax.set_title("singularity measures")
    return _save(fig, path, title, dpi=100)


def plot_episode(ep: Episode, path: str | Path) -> Path:
    """One HybridSingularityFree-v0 episode: Delta, the strokes, the
    singularity measures and the offsets along u."""
    u = np.array([i["u"] for i in ep.infos])
    lengths = np.array([i["lengths"] for i in ep.infos]) * 1000
    fig, axes = plt.subplots(1, 4, figsize=(16, 4))
    axes[0].plot(u, [i["delta"] for i in ep.infos])
    axes[0].set_ylabel("Delta")
    for k in range(9):
        axes[1].plot(u, lengths[:, k], color="tab:gray" if k < 6 else "tab:red", lw=1)
    axes[1].axhline(226.11, ls=":", color="k")
    axes[1].axhline(326.11, ls=":", color="k")
    axes[1].set_ylabel("leg length [mm]")
    axes[2].plot(u, [i["mu_hexapod"] for i in ep.infos], label="hexapod")
    axes[2].plot(u, [i["mu_tripod"] for i in ep.infos], label="tripod")
    axes[2].axhline(0.2, ls=":", color="k")
    axes[2].legend(fontsize=8)
    axes[2].set_ylabel("singularity measure")
    axes[3].plot(u, np.array([i["offset"] for i in ep.infos]) * 1000)
    axes[3].set_ylabel("offset x, y, z [mm]")
    for ax in axes:
        ax.set_xlabel("u")
    end = ep.infos[-1]
    return _save(fig, path, f"{ep.infos[0]['scenario'].name} scenario: success={end['is_success']}, "
                            f"return {ep.episode_return:.2f}")


