"""Pictures in the papers' form, written as PNG with matplotlib's Agg backend."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

from paragym.rollout import Episode  # noqa: E402
from paragym.sim.obstacles import Box, Cylinder  # noqa: E402

__all__ = ["plot_capaman_episode", "plot_episode", "plot_capaman_motion", "plot_hybrid_episode", "plot_hybrid_plan",
           "plot_imitation_curve", "plot_kappa_episode", "plot_leaderboard", "plot_orthoglide_cases",
           "plot_training_curve"]


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


def plot_capaman_episode(ep: Episode, path: str | Path, title: str = "") -> Path:
    """Paper 000's Fig 3 for one episode (see :func:`plot_capaman_motion`),
    against the step count."""
    alpha = np.array([i["alpha"] for i in ep.infos])
    tips = np.array([i["tool_tip"] for i in ep.infos])
    reached = [i["reached"] for i in ep.infos]
    marks = [k for k in range(1, len(reached)) if reached[k] > reached[k - 1]]
    end = ep.infos[-1]
    scenario = ep.infos[0]["scenario"]
    title = title or (f"{scenario.name} scenario: success={end['is_success']}, collision={end['collision']}, "
                      f"joint path {end['path_length']:.2f} rad, {len(ep.actions)} steps")
    return plot_capaman_motion(scenario, np.arange(len(alpha)), alpha, tips, marks, path, title,
                               frame=ep.frames[0] if ep.frames else None, time_label="step")


def plot_capaman_motion(scenario: Any, t: np.ndarray, alpha: np.ndarray, tips: np.ndarray,
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
        if isinstance(o, Cylinder):
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


def plot_hybrid_plan(plan: Any, path: str | Path, title: str = "", l_min: float = 0.22611,
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


def plot_hybrid_episode(ep: Episode, path: str | Path) -> Path:
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


def plot_orthoglide_cases(task: Any, cases: Sequence[Any], optimum: np.ndarray, geometry: Any,
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


def plot_kappa_episode(ep: Episode, path: str | Path) -> Path:
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


def plot_tripod_estimates(t: np.ndarray, true: np.ndarray, tracks: dict[str, np.ndarray], eta: np.ndarray,
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


def plot_leaderboard(summaries: Sequence[Any], key: str, label: str, path: str | Path, title: str = "",
                     higher_is_better: bool = False) -> Path:
    """One env's leaderboard as three bar panels, in rank order: success
    rate and mean return with their 95 % intervals (``success_ci``,
    ``return_ci`` of each summary), and the env's primary metric
    (which way is better written on its axis; its axis starts near the
    smallest value, not at 0, when the values differ by little). Bar
    colours are the policy kinds, in a legend."""
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
        base = 0.0
        finite = values[np.isfinite(values)]
        if i == 2 and len(finite) and finite.min() > 0 and np.ptp(finite) < 0.5 * finite.max():
            base = finite.min() - 0.1 * max(np.ptp(finite), 0.02 * finite.min())  # show the differences
        ax.barh(y, values - base, left=base, xerr=err, color=col, capsize=2)
        ax.set_xlabel(name)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(y, names)
    axes[0].invert_yaxis()
    axes[0].set_xlim(0, 1.05)
    kinds = [k for k in colours if any(s.kind == k for s in summaries)]
    fig.legend(handles=[Patch(color=colours[k], label=k) for k in kinds], loc="lower center", ncol=len(kinds),
               fontsize=8, frameon=False)
    return _save(fig, path, title, dpi=90, rect=(0, 0.5 / (0.45 * len(names) + 2.0), 1, 1))
