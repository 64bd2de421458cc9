"""The CaPaMan's pictures (paper 000): an episode's cranks and clearance, a planned motion among the obstacles."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle, Rectangle

from paragym.plots import _save
from paragym.rollout import Episode
from paragym.sim.obstacles import Box, Capsule, Cylinder

__all__ = ["plot_episode", "plot_motion"]


def plot_episode(ep: Episode, path: str | Path, title: str = "") -> Path:
    """Paper 000's Fig 3 for one episode (see :func:`plot_motion`),
    against the step count."""
    alpha = np.array([i["alpha"] for i in ep.infos])
    tips = np.array([i["tool_tip"] for i in ep.infos])
    reached = [i["reached"] for i in ep.infos]
    marks = [k for k in range(1, len(reached)) if reached[k] > reached[k - 1]]
    end = ep.infos[-1]
    scenario = ep.infos[0]["scenario"]
    title = title or (f"{scenario.name} scenario: success={end['is_success']}, collision={end['collision']}, "
                      f"joint path {end['path_length']:.2f} rad, {len(ep.actions)} steps")
    return plot_motion(scenario, np.arange(len(alpha)), alpha, tips, marks, path, title,
                               frame=ep.frames[0] if ep.frames else None, time_label="step")


def plot_motion(scenario: Any, t: np.ndarray, alpha: np.ndarray, tips: np.ndarray,
                        marks: Sequence[float], path: str | Path, title: str,
                        frame: np.ndarray | None = None, time_label: str = "t [s]") -> Path:
    """Paper 000's Fig 3: (a) the scene, (b) the tool-tip path seen from above
    with the obstacles, the T.C.s and the paper's 6 cm circle, (c) the joint
    path in the joint space, (d) the joint angles against ``t`` with dashed
    lines at ``marks`` (a T.C. reached). ``alpha`` in rad, ``tips`` in m."""
    alpha = np.degrees(alpha)
    tip = np.asarray(tips) * 1000.0
    tc = np.array(scenario.task_configs) * 1000.0
    tp = np.degrees(scenario.alpha)

    fig = plt.figure(figsize=(12, 9))
    ax = fig.add_subplot(2, 2, 1)
    if frame is not None:
        ax.imshow(frame)
    ax.set_axis_off()
    ax.set_title("(a) scene at T.C.1 (PyBullet)")

    ax = fig.add_subplot(2, 2, 2)
    for o in scenario.obstacles:
        cx, cy = o.center[0] * 1000, o.center[1] * 1000
        if isinstance(o, (Cylinder, Capsule)):
            ax.add_patch(Circle((cx, cy), o.radius * 1000, color="tab:red", alpha=0.5))
        elif isinstance(o, Box):
            hx, hy = o.half_extents[0] * 1000, o.half_extents[1] * 1000
            ax.add_patch(Rectangle((cx - hx, cy - hy), 2 * hx, 2 * hy, color="tab:red", alpha=0.5))
    ax.add_patch(Circle((0, 0), 60, fill=False, ls=":", color="gray", label="6 cm circle (paper)"))
    ax.plot(tip[:, 0], tip[:, 1], "k-", lw=1.5, label="tool tip")
    for k, (x, y, _) in enumerate(tc):
        ax.plot(x, y, "o", color="tab:blue")
        ax.annotate(f"T.C.{k + 1}", (x, y), textcoords="offset points", xytext=(5, 5))
    ax.set_aspect("equal")
    ax.set_xlim(-70, 70)
    ax.set_ylim(-70, 70)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("(b) tool-tip path, top view")

    ax = fig.add_subplot(2, 2, 3, projection="3d")
    ax.plot(alpha[:, 0], alpha[:, 1], alpha[:, 2], "k-")
    ax.scatter(tp[:, 0], tp[:, 1], tp[:, 2], color="tab:blue", s=30)
    for k, p in enumerate(tp):
        ax.text(p[0], p[1], p[2], f" T.P.{k + 1}")
    for setter in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        setter(45, 135)
    ax.set_xlabel("alpha1 [deg]")
    ax.set_ylabel("alpha2 [deg]")
    ax.set_zlabel("alpha3 [deg]")
    ax.set_title("(c) joint path")

    ax = fig.add_subplot(2, 2, 4)
    for j in range(3):
        ax.plot(t, alpha[:, j], label=f"alpha{j + 1}")
    for m in marks:
        ax.axvline(m, ls="--", color="gray", lw=0.8)
    ax.set_xlabel(time_label)
    ax.set_ylabel("crank angle [deg]")
    ax.legend(fontsize=8)
    ax.set_title("(d) joint variables (dashed: T.P. reached)")

    return _save(fig, path, title, dpi=110)


