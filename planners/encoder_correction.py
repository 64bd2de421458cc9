"""Estimators of the mobile tripod's drive units (paper 004, section 3, and beyond).

* :class:`OdometryEstimator`: the odometry alone (no correction).
* :class:`EncoderCorrection`, the paper's method: at every sample, the
  inter-unit distances from the encoders (eq 4, smoothed over about ten
  samples: the encoders' +-1 deg noise alone moves a distance by centimetres)
  against those of the estimate (eq 5); when the two distances that touch one
  unit disagree by more than ``threshold`` and the one opposite it agrees,
  that unit is the faulty one, and it is moved to the intersection of the
  circles about the other two (the solution nearer its estimate) — the
  single-fault assumption the paper states.
* :class:`FusionEstimator`: an unscented Kalman filter (filterpy) on the six
  horizontal unit coordinates, predicting with the odometric increments and
  updating with the three encoder distances; it weighs both sources and so
  copes with faults on several units at once.

All take ``update(odometric_increments (3, 2), eta_measured (3,), heights (3,))``
and keep ``estimate`` (3, 3).
"""

from __future__ import annotations

import math

import numpy as np

from paragym.mechanisms import tripod as mt

__all__ = ["EncoderCorrection", "EncoderTrustPolicy", "EstimatorPolicy", "FusionEstimator", "OdometryEstimator",
           "faulty_unit"]


def faulty_unit(estimate: np.ndarray, target: np.ndarray, threshold: float) -> int | None:
    """The paper's single-fault test (section 3): the unit whose two distances
    in ``estimate`` (3, 3) disagree with the encoder distances ``target`` (3,)
    by more than ``threshold`` (m) while the one opposite it agrees; None when
    no unit is singled out."""
    diff = np.abs(mt.distances(estimate[None])[0] - target)
    order = np.argsort(diff)
    if diff[order[1]] > threshold and diff[order[0]] < threshold:
        return int(order[0])
    return None


class OdometryEstimator:
    """Dead reckoning: the estimate moves by the odometric increments."""

    def __init__(self, start: np.ndarray, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY) -> None:
        self.estimate = np.array(start, float)
        self.geometry = geometry
        self.detected: tuple[int, str] | None = None

    def update(self, increments: np.ndarray, eta: np.ndarray, heights: np.ndarray) -> np.ndarray:
        self.estimate[:, :2] += increments
        self.estimate[:, 2] = heights
        return self.estimate


class EncoderCorrection(OdometryEstimator):
    """The paper's single-fault correction (module docstring). ``threshold``
    (m) defaults to the distance error that the encoder noise alone can make."""

    def __init__(self, start: np.ndarray, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY,
                 threshold: float = 0.01, smoothing: float = 0.1) -> None:
        super().__init__(start, geometry)
        self.threshold, self.smoothing = threshold, smoothing
        self._last_eta: np.ndarray | None = None
        self._target: np.ndarray | None = None

    def update(self, increments: np.ndarray, eta: np.ndarray, heights: np.ndarray) -> np.ndarray:
        super().update(increments, eta, heights)
        measured = mt.distances(mt.plate_frame_units(eta, self.geometry))[0]
        # the encoder distances averaged over the last samples (the encoders' +-1 deg noise alone
        # moves a distance by a few cm; a fault is a lasting change): exponential smoothing
        self._target = measured if self._target is None else \
            self._target + self.smoothing * (measured - self._target)
        target = self._target
        self.detected = None
        faulty = faulty_unit(self.estimate, target, self.threshold)
        if faulty is not None:
            self.estimate = mt.relocate(self.estimate, faulty, target)
            # eta is measured down from the plate: a unit moved inward stands its leg up (eta grows), one
            # moved outward lays it down — the paper's reading of the sign, for this convention of eta
            kind = "unknown" if self._last_eta is None else (
                "inward (bump or push)" if eta[faulty] > self._last_eta[faulty] else "outward (hole or slip)")
            self.detected = (faulty, kind)
        self._last_eta = np.array(eta)
        return self.estimate


class FusionEstimator(OdometryEstimator):
    """A UKF (filterpy) on the units' horizontal coordinates (module docstring).

    Args:
        odometry_noise: std of the odometric error per unit and axis (m/s).
        encoder_noise: half-width of the uniform encoder noise (rad), turned
            into a distance std through the encoder distances' sensitivity.
        dt: sampling period (s).
    """

    def __init__(self, start: np.ndarray, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY,
                 odometry_noise: float = 0.01, encoder_noise: float = math.radians(1.0), dt: float = 0.05) -> None:
        from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

        super().__init__(start, geometry)
        self._heights = self.estimate[:, 2].copy()
        points = MerweScaledSigmaPoints(6, alpha=0.1, beta=2.0, kappa=0.0)
        self.ukf = UnscentedKalmanFilter(6, 3, dt, hx=self._hx, fx=self._fx, points=points)
        self.ukf.x = self.estimate[:, :2].ravel().copy()
        self.ukf.P = np.eye(6) * 1e-6
        self.ukf.Q = np.eye(6) * (odometry_noise * dt) ** 2
        sigma_eta = encoder_noise / math.sqrt(3)  # std of a uniform +-encoder_noise
        self._sigma_eta = sigma_eta
        self.ukf.R = np.eye(3) * (geometry.r * sigma_eta) ** 2

    def _fx(self, x: np.ndarray, dt: float, increments: np.ndarray | None = None) -> np.ndarray:
        return x if increments is None else x + increments.ravel()

    def _hx(self, x: np.ndarray) -> np.ndarray:
        units = np.column_stack([x.reshape(3, 2), self._heights])
        return mt.distances(units[None])[0]

    def update(self, increments: np.ndarray, eta: np.ndarray, heights: np.ndarray) -> np.ndarray:
        self._heights = np.asarray(heights, float)
        target = mt.distances(mt.plate_frame_units(eta, self.geometry))[0]
        self.ukf.predict(increments=increments)
        self.ukf.update(target)
        self.estimate = np.column_stack([self.ukf.x.reshape(3, 2), self._heights])
        return self.estimate


class EstimatorPolicy:
    """Any of these estimators as a ``MobileTripodOdometry-v0`` policy: it
    runs the estimator on what the env reports (odometry and encoders, up to
    the current sample) and corrects the env's estimate toward it (one sample
    behind, since the next odometric increment is not known yet)."""

    def __init__(self, estimator: type = EncoderCorrection, max_correction: float = 0.05,
                 geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY) -> None:
        self.kind, self.max_correction, self.geometry = estimator, max_correction, geometry
        self.estimator: OdometryEstimator | None = None

    def reset(self, obs: np.ndarray, info: dict) -> None:
        self.estimator = self.kind(info["odometry"], self.geometry)
        self._odometry = np.array(info["odometry"])

    def act(self, obs: np.ndarray, info: dict) -> np.ndarray:
        if self.estimator is None:
            raise RuntimeError("call reset(obs, info) before act")
        odometry = np.asarray(info["odometry"])
        increments = odometry[:, :2] - self._odometry[:, :2]
        self._odometry = odometry.copy()
        if np.any(increments):
            self.estimator.update(increments, info["eta"], odometry[:, 2])
        wanted = self.estimator.estimate[:, :2] - np.asarray(info["estimate"])[:, :2]
        return np.clip(wanted.ravel() / self.max_correction, -1, 1).astype(np.float32)


class EncoderTrustPolicy:
    """The paper's correction as a ``MobileTripodOdometry-v1`` policy: the
    env keeps the estimate and the smoothed encoder distances (the same
    smoothing as :class:`EncoderCorrection`), and moves a unit toward the
    circle intersection as far as the action trusts it. This policy trusts
    fully the unit that the paper's single-fault test singles out
    (:func:`faulty_unit`) and no other; the env then moves it
    ``trust_rate`` (0.2) of the way per sample rather than at once."""

    def __init__(self, threshold: float = 0.01) -> None:
        self.threshold = threshold

    def reset(self, obs: np.ndarray, info: dict) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict) -> np.ndarray:
        action = np.zeros(3, np.float32)
        faulty = faulty_unit(np.asarray(info["estimate"]), np.asarray(info["encoder_distances"]), self.threshold)
        if faulty is not None:
            action[faulty] = 1.0
        return action
