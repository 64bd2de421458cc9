"""The verdict: does an executed motion match the planned one? (paper 000, section 5)

:func:`validate` puts the simulated accelerometers on the executed motion,
inverts their readings before and after the Kalman filter (eq 17), and
compares the plate-centre acceleration a_H and the angular velocity omega,
in the body frame, with the planned motion's theoretical values: RMSE and
peak error of the raw and of the filtered estimate, the noise-reduction
factor, the normalised cross-correlation of the filtered estimate with the
theory, and a pass/fail per component and overall with the tolerances
written in the report. :func:`plot_report` draws the paper's Figs 8 and 9.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from paragym.trajectories import RigidMotion
from paragym.validation.kalman import KalmanSettings, filter_vectorised, smooth_vectorised
from paragym.validation.sensors import GRAVITY, AccelerometerArray, angular_velocity_from_z

__all__ = ["ComponentReport", "MotionTooShort", "Tolerances", "ValidationReport", "plot_report", "validate",
           "write_report"]

#: the fewest sensor samples the planned and the executed motion must share to be validated
MIN_SAMPLES = 10


class MotionTooShort(ValueError):
    """The planned and executed motions share fewer than :data:`MIN_SAMPLES` sensor samples: nothing to judge."""

COMPONENTS = ("a_Hx", "a_Hy", "a_Hz", "omega_x", "omega_y", "omega_z")
UNITS = {"a": "m/s^2", "o": "rad/s"}


@dataclass(frozen=True)
class Tolerances:
    """A component passes when the judged estimate's RMSE against the theory
    is at most ``noise * floor + rel * RMS(theory)``, where ``floor`` is the
    RMS of the same estimate for a body at rest (the sensor noise the filter
    leaves; measured, not assumed), and, where the theory's RMS exceeds
    twice that floor, the correlation with the theory is at least
    ``min_correlation``. Angular velocities from centripetal terms sit far
    below the noise for slow motions: there the floor decides."""

    noise: float = 2.0
    rel: float = 0.25
    min_correlation: float = 0.8


@dataclass(frozen=True)
class ComponentReport:
    """One component's figures (units of the component)."""

    name: str
    rms_theory: float
    rmse_raw: float
    rmse_kf: float
    peak_error_raw: float
    peak_error_kf: float
    noise_reduction: float
    error_judged: float  # RMSE of the judged estimate against the plan seen through the same filter
    correlation: float
    tolerance: float
    passed: bool
    observable: bool  # the reference stands above twice the noise floor (else only the error bound is checked)

    @property
    def label(self) -> str:
        """The component's verdict as the table and the figures write it: "pass", "FAIL", and a "*" where the
        component lies below the noise floor (only its error bound was checked)."""
        return ("pass" if self.passed else "FAIL") + ("" if self.observable else "*")


@dataclass(frozen=True)
class ValidationReport:
    """Per-component figures, the verdict, and the series behind them
    (body frame, on the sensors' time grid)."""

    components: tuple[ComponentReport, ...]
    passed: bool
    tolerances: Tolerances
    judged: str  # "smoothed" (KF + RTS, offline) or "filtered" (the forward KF)
    t: np.ndarray = field(repr=False)
    theory: np.ndarray = field(repr=False)  # (N, 6): a_H (3), omega (3)
    raw: np.ndarray = field(repr=False)
    filtered: np.ndarray = field(repr=False)
    smoothed: np.ndarray = field(repr=False)
    reference: np.ndarray = field(repr=False)  # the plan seen through the judged filter
    floor: np.ndarray = field(repr=False)  # (6,) the judged estimate's RMS at rest
    eq21_gap: float = 0.0  # largest difference between eq 21's direct a_H and eq 17's, filtered (m/s^2)

    def table(self) -> str:
        """The report as a fixed-width text table."""
        head = (f"{'component':10s} {'RMS theory':>11s} {'RMSE raw':>9s} {'RMSE KF':>8s} {'peak raw':>9s} "
                f"{'peak KF':>8s} {'noise x':>8s} | {'error':>7s} {'tol':>7s} {'corr':>6s}  verdict")
        rows = [head]
        for c in self.components:
            rows.append(f"{c.name:10s} {c.rms_theory:11.4f} {c.rmse_raw:9.4f} {c.rmse_kf:8.4f} "
                        f"{c.peak_error_raw:9.4f} {c.peak_error_kf:8.4f} {c.noise_reduction:8.1f} | "
                        f"{c.error_judged:7.4f} {c.tolerance:7.4f} {c.correlation:6.2f}  "
                        f"{c.label}")
        tol = self.tolerances
        rows.append(f"left of |: estimates against the plan's theoretical values; 'noise x' = RMSE raw / RMSE KF. "
                    f"Right of |: the {self.judged} estimate against the plan seen through the same filter.")
        rows.append(f"verdict: {'PASS' if self.passed else 'FAIL'} (error <= {tol.noise} x the estimate's RMS at "
                    f"rest + {tol.rel} x the reference's RMS; correlation >= {tol.min_correlation} where the "
                    f"reference stands above twice that noise). a_H in m/s^2, omega in rad/s. * below the noise "
                    f"floor: the sensors cannot see this component here, only the error bound is checked.")
        return "\n".join(rows)


def _estimates(z: np.ndarray, t: np.ndarray) -> np.ndarray:
    """a_H and omega (N, 6), body frame, from z of gravity-compensated readings."""
    return np.column_stack([z[:, :3], angular_velocity_from_z(z, t)])


def _without_gravity(y: np.ndarray, sensors: AccelerometerArray, rotation: np.ndarray) -> np.ndarray:
    """Readings less what gravity contributes at the planned attitude (eq 12's
    -g term), so that the filter sees the motion only; an execution whose
    attitude departs from the plan leaves gravity in, and the verdict sees it."""
    minus_g_body = -np.einsum("nji,j->ni", rotation, GRAVITY)
    return y - minus_g_body @ sensors.matrix[:, :3].T


def validate(planned: RigidMotion, executed: RigidMotion, sensors: AccelerometerArray | None = None,
             kalman: KalmanSettings | None = None, tolerances: Tolerances | None = None,
             seed: int = 0, smoother: bool = True) -> ValidationReport:
    """Validate ``executed`` against ``planned`` (both about the same body
    point; the sensors sample both on their own grid over the time they share, each sample the mean over its
    period, :meth:`AccelerometerArray.read_mean`).

    The readings, less gravity at the planned attitude, are inverted raw,
    after the forward Kalman filter (the paper's), and after an RTS smoother
    on that filter (offline, no lag).
    The verdict judges the smoothed estimate (``smoother=False``: the
    filtered one); the report carries all three.
    """
    sensors = sensors or AccelerometerArray.paper_layout()
    kalman = kalman or KalmanSettings()
    tolerances = tolerances or Tolerances()
    end = min(planned.t[-1], executed.t[-1])
    t = np.arange(max(planned.t[0], executed.t[0]), end + 1e-12, 1.0 / sensors.rate)
    if len(t) < MIN_SAMPLES:
        raise MotionTooShort(f"planned and executed motions share fewer than {MIN_SAMPLES} sensor samples")
    plan = planned.at(t)
    dt = 1.0 / sensors.rate
    y_raw = _without_gravity(sensors.read_mean(executed, t, np.random.default_rng(seed)), sensors, plan.rotation)
    y_kf = filter_vectorised(y_raw, dt, kalman)
    z_kf = sensors.invert(y_kf)
    raw = _estimates(sensors.invert(y_raw), t)
    filtered = _estimates(z_kf, t)
    smoothed = _estimates(sensors.invert(smooth_vectorised(y_raw, dt, kalman)), t)
    theory = np.column_stack([plan.body("acceleration"), plan.body("angular_velocity")])
    f_direct, _ = sensors.direct(y_kf)
    eq21_gap = float(np.abs(f_direct - z_kf[:, :3]).max())

    # The reference for the verdict: the plan as this sensor and filter chain would report it
    # (noise-free readings of the planned motion through the same filter), so that the filter's
    # own lag and smoothing, which the raw theory does not have, are not held against the execution.
    smooth = smooth_vectorised if smoother else filter_vectorised
    y_plan = _without_gravity(sensors.read_mean(planned, t), sensors, plan.rotation)
    reference = _estimates(sensors.invert(smooth(y_plan, dt, kalman)), t)
    judged = smoothed if smoother else filtered
    floor = _noise_floor(sensors, kalman, len(t), seed, smoother)
    comps = []
    for j, name in enumerate(COMPONENTS):
        err_raw, err_kf = raw[:, j] - theory[:, j], filtered[:, j] - theory[:, j]
        rms = float(np.sqrt(np.mean(reference[:, j] ** 2)))
        rmse_raw, rmse_kf = float(np.sqrt(np.mean(err_raw ** 2))), float(np.sqrt(np.mean(err_kf ** 2)))
        rmse_judged = float(np.sqrt(np.mean((judged[:, j] - reference[:, j]) ** 2)))
        tol = tolerances.noise * floor[j] + tolerances.rel * rms
        corr = _correlation(judged[:, j], reference[:, j])
        signal = rms > 2 * floor[j]
        passed = rmse_judged <= tol and (not signal or corr >= tolerances.min_correlation)
        comps.append(ComponentReport(name, float(np.sqrt(np.mean(theory[:, j] ** 2))), rmse_raw, rmse_kf,
                                     float(np.abs(err_raw).max()), float(np.abs(err_kf).max()),
                                     rmse_raw / max(rmse_kf, 1e-12), rmse_judged, corr, tol, bool(passed),
                                     bool(signal)))
    return ValidationReport(tuple(comps), all(c.passed for c in comps), tolerances,
                            "smoothed" if smoother else "filtered", t, theory, raw, filtered, smoothed, reference,
                            floor, eq21_gap)


def _correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation at zero lag (0 when either is constant)."""
    a, b = a - a.mean(), b - b.mean()
    den = np.sqrt(np.sum(a * a) * np.sum(b * b))
    return float(np.sum(a * b) / den) if den > 0 else 0.0


_FLOORS: dict[tuple, np.ndarray] = {}


def _noise_floor(sensors: AccelerometerArray, kalman: KalmanSettings, n: int, seed: int,
                 smoother: bool) -> np.ndarray:
    """RMS of the six judged estimates for a level body at rest (N samples, a
    tenth cut at each end for the filter's start). Kept per sensors, filter,
    length and seed: a leaderboard validates many episodes of one length."""
    key = (sensors.positions.tobytes(), sensors.axes.tobytes(), sensors.offsets.tobytes(), sensors.noise_std,
           sensors.rate, repr(kalman), n, seed, smoother)
    if key not in _FLOORS:
        if len(_FLOORS) > 64:
            _FLOORS.clear()
        _FLOORS[key] = _rest_floor(sensors, kalman, n, seed, smoother)
    return _FLOORS[key].copy()


def _rest_floor(sensors: AccelerometerArray, kalman: KalmanSettings, n: int, seed: int,
                smoother: bool) -> np.ndarray:
    t = np.arange(n) / sensors.rate
    zero = np.zeros((n, 3))
    rest = RigidMotion(t, zero, np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), zero, zero, zero, zero)
    y = _without_gravity(sensors.read(rest, np.random.default_rng(seed + 1)), sensors, rest.rotation)
    smooth = smooth_vectorised if smoother else filter_vectorised
    est = _estimates(sensors.invert(smooth(y, 1.0 / sensors.rate, kalman)), t)
    return np.sqrt(np.mean(est[n // 10:n - n // 10] ** 2, axis=0))


def plot_report(report: ValidationReport, out_dir: str | Path, title: str = "") -> list[Path]:
    """Paper 000's Fig 8 (raw estimates against time) and Fig 9 (filtered
    estimate over the theoretical curve), one panel per component; PNG files."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for fig_name, series, label in (("fig8_raw", report.raw, "raw (eq 17 on the readings)"),
                                    ("fig9_kf", report.filtered, "Kalman-filtered (forward)")):
        fig, axes = plt.subplots(3, 2, figsize=(12, 9), sharex=True)
        for j, c in enumerate(report.components):
            ax = axes[j % 3, j // 3]
            ax.plot(report.t, series[:, j], lw=0.6, color="tab:gray" if fig_name == "fig8_raw" else "tab:blue",
                    label=label)
            if fig_name == "fig9_kf":
                ax.plot(report.t, report.smoothed[:, j], lw=0.8, color="tab:orange", label="KF + RTS smoother")
            ax.plot(report.t, report.theory[:, j], lw=1.2, color="k", label="theoretical (plan)")
            unit = UNITS[c.name[0]]
            ax.set_ylabel(f"{c.name} [{unit}]")
            ax.set_title(f"{c.name}: RMSE {c.rmse_kf if fig_name == 'fig9_kf' else c.rmse_raw:.3f} {unit}"
                         f" — {c.label}", fontsize=9)
        for ax in axes[-1]:
            ax.set_xlabel("t [s]")
        axes[0, 0].legend(fontsize=8)
        hidden = "" if all(c.observable for c in report.components) else (
            "; * below the noise floor: only the error bound is checked")
        fig.suptitle((title + "\n" if title else "") + ("Fig 8 form: measured (raw)" if fig_name == "fig8_raw"
                                                        else "Fig 9 form: Kalman filter over theory") + hidden)
        fig.tight_layout()
        path = out / f"{fig_name}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        paths.append(path)
    return paths


def write_report(report: ValidationReport, out_dir: str | Path, title: str, facts: dict[str, Any]) -> int:
    """Save a validation: Figs 8-9 (:func:`plot_report`) and ``report.json`` in ``out_dir``, the verdict with
    its tolerances and components beside ``facts`` (what was validated, how it was run); say what was written.
    Returns the command's exit code: 0 when the report passed, else 1. The one writer of every task's
    validation report (``paragym validate``, the benches' reference plans)."""
    import json
    from dataclasses import asdict

    out_dir = Path(out_dir)
    paths = plot_report(report, out_dir, title)
    (out_dir / "report.json").write_text(json.dumps({
        **facts, "passed": report.passed, "judged": report.judged, "tolerances": asdict(report.tolerances),
        "components": [asdict(c) for c in report.components]}, indent=2, default=repr))
    print(f"wrote {', '.join(str(p) for p in paths)} and {out_dir / 'report.json'}")
    return 0 if report.passed else 1
