"""paragym.validation: the sensor model and its inversion, the filter against
filterpy, the dynamic CaPaMan, and a verdict that passes and fails."""

import numpy as np
import pytest

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import quat_to_matrix
from paragym.sim.capaman_dynamic import CaPaManDynamics, CaPaManDynamicScene
from paragym.trajectories import JointPath, JointTrajectory
from paragym.validation.capaman import validate_capaman
from paragym.validation.kalman import filter_filterpy, filter_vectorised, smooth_filterpy, smooth_vectorised
from paragym.validation.motion import RigidMotion
from paragym.validation.sensors import AccelerometerArray, angular_velocity_from_z, design_rows


def _tumbling(n: int = 400) -> RigidMotion:
    """A known rigid-body motion: spinning about a wobbling axis while translating."""
    t = np.linspace(0, 2, n)
    w = np.column_stack([0.8 * np.sin(2 * t), 0.5 * np.cos(3 * t), 1.2 + 0.3 * t])
    al = np.column_stack([1.6 * np.cos(2 * t), -1.5 * np.sin(3 * t), np.full(n, 0.3)])
    rot = np.stack([quat_to_matrix(np.array([np.sin(a / 2) * 0.6, 0.0, np.sin(a / 2) * 0.8,
                                                      np.cos(a / 2)])) for a in t])
    acc = np.column_stack([np.sin(t), -np.cos(2 * t), 0.3 * t])
    zero = np.zeros((n, 3))
    return RigidMotion(t, zero, rot, zero, w, acc, al)


def test_noise_free_readings_invert_to_the_motion():
    sensors = AccelerometerArray.paper_layout()
    motion = _tumbling()
    z = sensors.invert(sensors.read(motion))
    np.testing.assert_allclose(z, AccelerometerArray.true_z(motion), atol=1e-10)
    np.testing.assert_allclose(angular_velocity_from_z(z, motion.t), motion.body("angular_velocity"), atol=1e-7)
    # eq 21's direct formulas give the same specific force at H and the same |omega|
    f_h, w_abs = sensors.direct(sensors.read(motion))
    np.testing.assert_allclose(f_h, z[:, :3], atol=1e-10)
    np.testing.assert_allclose(w_abs, np.abs(motion.body("angular_velocity")), atol=1e-6)


def test_coplanar_sensors_cannot_be_inverted():
    """Why the default layout puts two sensors on a bracket below the plate."""
    positions = np.repeat([[0.15, 0, 0], [-0.15, 0, 0], [0, 0.15, 0], [0, -0.15, 0]], 3, axis=0)
    flat = design_rows(positions, np.tile(np.eye(3), (4, 1)))
    assert np.linalg.matrix_rank(flat) < 12
    assert np.linalg.matrix_rank(AccelerometerArray.paper_layout().matrix) == 12


def test_readings_carry_gravity_offsets_and_noise():
    sensors = AccelerometerArray.paper_layout()
    n = 2000
    t = np.arange(n) / sensors.rate
    zero = np.zeros((n, 3))
    rest = RigidMotion(t, zero, np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), zero, zero, zero, zero)
    y = sensors.read(rest, np.random.default_rng(0))
    expected = np.tile([0.0, 0.0, 9.81], 4) + sensors.offsets  # a level body at rest feels +g on z
    np.testing.assert_allclose(y.mean(axis=0), expected, atol=0.05)
    np.testing.assert_allclose(y.std(axis=0), 0.5, rtol=0.1)


@pytest.mark.parametrize("vectorised, reference", [(filter_vectorised, filter_filterpy),
                                                   (smooth_vectorised, smooth_filterpy)])
def test_vectorised_filters_match_filterpy(vectorised, reference):
    rng = np.random.default_rng(1)
    t = np.arange(3000) / 500
    y = np.sin(np.outer(t, np.arange(1, 13) * 0.7)) + rng.normal(0, 0.5, (3000, 12))
    np.testing.assert_allclose(vectorised(y, 1 / 500), reference(y, 1 / 500), atol=1e-9, rtol=0)


def test_filter_input_is_checked():
    with pytest.raises(ValueError, match="readings"):
        filter_vectorised(np.zeros((10, 4)), 0.01)
    with pytest.raises(ValueError, match="dt"):
        filter_vectorised(np.zeros((10, 3)), -1.0)


@pytest.fixture(scope="module")
def plan(paper_result):
    return paper_result


@pytest.fixture(scope="module")
def scene():
    s = CaPaManDynamicScene()
    yield s
    s.close()


def test_slow_dynamic_run_follows_the_kinematics_and_stays_closed(plan, scene):
    leg = JointPath(plan.path.waypoints[:8], (0, 7))  # T.P.1 -> T.P.2 at the paper's slow pace
    traj = JointTrajectory.from_path(leg, 0.9)
    run = scene.execute(traj, settle=0.3)
    pose = capaman.forward(np.clip(traj.position(run.t), capaman.DEG * 45, capaman.DEG * 135))
    assert np.linalg.norm(run.position - pose.position, axis=1).max() < 0.5e-3  # 0.5 mm
    assert run.closure_error < 0.05e-3  # the six loop closures hold to 50 micrometres


def test_fast_execution_differs_from_the_plan_physically(plan, scene):
    traj = plan.trajectory(0.09)
    run = scene.execute(traj, settle=0.3)
    lag = np.abs(run.alpha - traj.position(run.t)).max()
    assert 1e-4 < lag < np.radians(2)  # not a copy of the plan, not lost either


@pytest.mark.slow
def test_verdict_passes_a_good_execution_and_fails_bad_ones(plan, scene):
    traj = plan.trajectory(0.09)
    good = validate_capaman(traj, scene=scene)
    assert good.report.passed, good.report.table()
    assert good.report.eq21_gap < 1e-9
    late = validate_capaman(traj, scene=scene, delay=0.1)
    assert not late.report.passed
    weak = validate_capaman(plan.trajectory(0.45), dynamics=CaPaManDynamics(motor_torque=0.3))
    assert not weak.report.passed


def test_the_figures_mark_a_component_below_the_noise_floor_as_the_table_does(plan, scene, tmp_path, monkeypatch):
    """A component the sensors cannot see is "pass*" in the table; the figures used to call it "pass"."""
    import matplotlib.pyplot as plt

    from paragym.validation.report import plot_report

    report = validate_capaman(plan.trajectory(0.09), scene=scene).report
    hidden = [c for c in report.components if not c.observable]
    assert hidden, "the paper's fast case has components below the noise floor (the angular velocities)"
    titles: list[str] = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: (titles.extend(ax.get_title() for ax in fig.axes),
                                                         close(fig)))
    plot_report(report, tmp_path)
    for c in hidden:
        assert f"{c.label}" in report.table() and c.label.endswith("*")
        assert any(t.startswith(f"{c.name}:") and t.endswith(f"— {c.label}") for t in titles), titles


def _still_with_chatter(amplitude: float, hz: float, step: float = 5e-4, seconds: float = 3.0) -> RigidMotion:
    """A level body at rest, shaken vertically at ``hz`` with an acceleration of ``amplitude`` (m/s^2), on a
    simulation's grid of ``step`` s."""
    t = np.arange(0.0, seconds + step / 2, step)
    w = 2 * np.pi * hz
    zero = np.zeros((len(t), 3))
    position, velocity, acceleration = zero.copy(), zero.copy(), zero.copy()
    position[:, 2] = -amplitude / w**2 * np.sin(w * t)
    velocity[:, 2] = -amplitude / w * np.cos(w * t)
    acceleration[:, 2] = amplitude * np.sin(w * t)
    return RigidMotion(t, position, np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(), velocity, zero, acceleration,
                       zero)


def test_a_sensor_sample_is_its_periods_mean_so_chatter_above_its_band_does_not_fold_into_it():
    """An accelerometer sampled at 100 Hz reads each period's mean (a real one's anti-aliasing filter): a body
    shaken at 399.7 Hz, far above its 50 Hz band, reads within 2 % of the shaking of gravity alone, and the KF
    check passes it against the body at rest; read at the instant, the shaking folds to 0.3 Hz, where the
    filter keeps it, and fails the check."""
    from paragym.validation.report import validate

    sensors = AccelerometerArray.paper_layout(r=0.3, depth=0.1, rate=100.0)
    shaken, still = _still_with_chatter(1.0, 399.7), _still_with_chatter(0.0, 399.7)
    t = np.arange(0.0, 3.0 + 1e-9, 0.01)
    folded = sensors.read(shaken.at(t))[:, 2] - sensors.read(still.at(t))[:, 2]
    meaned = sensors.read_mean(shaken, t)[:, 2] - sensors.read_mean(still, t)[:, 2]
    assert np.abs(folded).max() > 0.5 and np.abs(meaned).max() < 0.02, (np.abs(folded).max(), np.abs(meaned).max())
    assert validate(still, shaken, sensors).passed
