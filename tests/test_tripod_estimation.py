"""Paper 004's scenarios: odometry, the redundant-encoder correction and the fusion estimator."""

import math

import gymnasium as gym
import numpy as np
import pytest

import paragym  # noqa: F401
from paragym.planners.encoder_correction import (
    EncoderCorrection,
    EstimatorPolicy,
    FusionEstimator,
    OdometryEstimator,
)
from paragym.rollout import run_episode
from paragym.sim.tripod_drive import TripodDrive
from paragym.tasks.tripod import drive_scenario


def _final_error(scenario_name: str, kind: type, seed: int = 0) -> tuple[float, list]:
    scenario = drive_scenario(scenario_name, np.random.default_rng(seed))
    drive = TripodDrive(scenario, np.random.default_rng(seed))
    est = kind(drive.odometry)
    detections = []
    for _ in range(drive.steps):
        inc = drive.step()
        est.update(inc, drive.encoders, drive.odometry[:, 2])
        if est.detected:
            detections.append((round(drive.t, 2), *est.detected))
    return float(np.linalg.norm(est.estimate[:, :2] - drive.true[:, :2], axis=1).max()), detections


@pytest.mark.parametrize("name", ["initial_heading", "push"])
def test_correction_is_ten_times_better_than_odometry(name):
    odometry, _ = _final_error(name, OdometryEstimator)
    corrected, detections = _final_error(name, EncoderCorrection)
    assert corrected * 10 < odometry, (corrected, odometry)
    if name == "push":  # the push on unit 1 at t = 15 s is seen, as inward
        assert any(t >= 15.0 and unit == 0 and kind.startswith("inward") for t, unit, kind in detections)


def test_fusion_beats_the_single_fault_correction_when_all_units_slip():
    corrected, _ = _final_error("random_slip", EncoderCorrection)
    fused, _ = _final_error("random_slip", FusionEstimator)
    assert fused < corrected


def test_a_single_fault_is_recovered_within_the_encoder_noise():
    from paragym.mechanisms import tripod as mt

    drive = TripodDrive(drive_scenario("push", np.random.default_rng(0)), np.random.default_rng(0))
    est = EncoderCorrection(drive.odometry)
    for _ in range(drive.steps):
        est.update(drive.step(), drive.encoders, drive.odometry[:, 2])
    bound = 2 * mt.DEFAULT_GEOMETRY.r * math.radians(1.0)  # two legs' worth of +-1 deg
    assert np.linalg.norm(est.estimate[:, :2] - drive.true[:, :2], axis=1).max() < bound


def test_env_estimators_rank_as_in_the_paper():
    env = gym.make("paragym/MobileTripodOdometry-v0", scenario="initial_heading")
    odo = run_episode(env, EstimatorPolicy(OdometryEstimator), seed=0)
    cor = run_episode(env, EstimatorPolicy(EncoderCorrection), seed=0)
    assert cor.infos[-1]["unit_error"] * 10 < odo.infos[-1]["unit_error"]
    assert cor.episode_return > odo.episode_return and cor.success and not odo.success


def test_bad_scenarios_are_refused():
    with pytest.raises(ValueError, match="scenario must be"):
        gym.make("paragym/MobileTripodOdometry-v0", scenario="moon")
