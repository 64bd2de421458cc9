"""The mobile tripod's pictures (paper 004): the estimates of the drive units against the truth."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from paragym.plots import _save

__all__ = ["plot_estimates"]


def plot_estimates(t: np.ndarray, true: np.ndarray, tracks: dict[str, np.ndarray], eta: np.ndarray,
                          eta_true: np.ndarray, unit: int, path: str | Path, title: str) -> Path:
    """Paper 004's Figs 8-10: the path of one drive unit — true, odometric and
    corrected — with the lateral offset magnified; eta of that unit over time;
    each estimator's error over time. ``true`` (T, 3, 3), tracks name -> (T, 3, 3)."""
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    ax = axes[0]
    ax.plot(true[:, unit, 0], true[:, unit, 1] * 100, "k", lw=2, label="true")
    for name, est in tracks.items():
        ax.plot(est[:, unit, 0], est[:, unit, 1] * 100, lw=1, label=name)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [cm]")
    ax.set_title(f"path of drive unit {unit + 1}")
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.plot(t, np.degrees(eta[:, unit]), lw=0.6, color="tab:gray", label="measured (+-1 deg noise)")
    ax.plot(t, np.degrees(eta_true[:, unit]), "k", lw=1.2, label="true")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"eta_{unit + 1} [deg]")
    ax.legend(fontsize=8)
    ax.set_title("encoder angle")
    ax = axes[2]
    for name, est in tracks.items():
        ax.plot(t, np.linalg.norm(est[:, :, :2] - true[:, :, :2], axis=2).max(axis=1) * 100, label=name)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("largest unit error [cm]")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.set_title("estimation error")
    return _save(fig, path, title)


