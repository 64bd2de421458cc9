"""The MuJoCo dynamic fidelity (``engine="mujoco"``, paragym.sim.mujoco_sim): the same envs, scenes and checks
as PyBullet's, with MuJoCo's physics."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import paragym  # noqa: F401
from paragym import registry

mujoco = pytest.importorskip("mujoco")

from paragym.sim.client import PyBulletSim  # noqa: E402
from paragym.sim.mujoco_sim import MuJoCoSettings, MuJoCoSim  # noqa: E402

#: the ids whose task runs MuJoCo, and how far (m) the engines may part on the reference's paper episode
IDS = {"paragym/CaPaManCollisionFree-v1": 5e-4, "paragym/HybridSingularityFree-v2": 2e-3,
       "paragym/Orthoglide2PRRKappa-v2": 2e-3}  # the 2PRR's motors in PyBullet lag a 5 ms step: 1.26 mm
#: how far (m) a loop may open in MuJoCo under random actions (PyBullet on the same actions: 0.0007 and 0.64 mm)
LOOPS = {"paragym/CaPaManCollisionFree-v1": 5e-5, "paragym/HybridSingularityFree-v2": 5e-4,
         "paragym/Orthoglide2PRRKappa-v2": 5e-5}


def make(env_id: str, engine: object = "mujoco", **kwargs: object) -> gym.Env:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gym.make(env_id, fidelity="dynamic", engine=engine, **kwargs)


@pytest.mark.parametrize("preset", ["default", "fast"])
@pytest.mark.parametrize("env_id", IDS)
def test_mujoco_runs_the_env_with_its_spaces_and_loops_closed(env_id, preset):
    """The env's spaces are the same in both engines; in MuJoCo, at either preset, random in-Box actions keep
    every loop closed (CaPaMan and 2PRR within 0.05 mm, hybrid 0.5 mm), as ``info["loop_residual_m"]`` reports it every
    step, and the engine steps at the preset's step."""
    settings = MuJoCoSettings() if preset == "default" else MuJoCoSettings.fast()
    env, reference = make(env_id, settings), make(env_id, "pybullet")
    assert env.unwrapped.physics_time_step == settings.time_step
    try:
        assert env.observation_space == reference.observation_space
        assert env.action_space == reference.action_space
        assert isinstance(env.unwrapped.world.scene.sim, MuJoCoSim)
        assert isinstance(reference.unwrapped.world.scene.sim, PyBulletSim)
        obs, _ = env.reset(seed=1)
        assert env.observation_space.contains(obs)
        env.action_space.seed(1)
        for _ in range(20):
            obs, _, terminated, truncated, info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs)
            assert 0 < info["loop_residual_m"] < LOOPS[env_id], info["loop_residual_m"]
            if terminated or truncated:
                break
    finally:
        env.close()
        reference.close()


@pytest.mark.parametrize("env_id", IDS)
def test_the_engines_execute_the_reference_alike(env_id):
    """The paper's method on the paper's case in both engines: it succeeds and passes the KF check in each, and
    the validated body's executed paths stay within the id's tolerance of each other (CaPaMan 0.5 mm, hybrid
    and 2PRR 2 mm); MuJoCo's recorder samples at MuJoCo's 1 ms step."""
    from paragym.baselines.policies import get_policy
    from paragym.baselines.tasks import bench_of
    from paragym.validation.episode import validate_episode

    spec = get_policy(env_id, bench_of(env_id).reference)
    runs = {}
    for engine in ("pybullet", "mujoco"):
        env = make(env_id, engine, scenario=registry.row(env_id).paper_scenario)
        try:
            runs[engine] = val = validate_episode(env, spec.factory(env, 0), seed=0, sensor_seed=0)
        finally:
            env.close()
        assert val.success and val.passed, (engine, val.report)
    ours, theirs = runs["mujoco"].executed, runs["pybullet"].executed
    assert np.allclose(np.diff(ours.t), MuJoCoSettings().time_step)
    on_grid = ours.at(theirs.t[theirs.t <= ours.t[-1]])
    gap = np.linalg.norm(on_grid.position - theirs.position[:len(on_grid.t)], axis=1).max()
    assert gap < IDS[env_id], gap


def test_a_reset_starts_mujoco_afresh():
    """An episode from a seed is the same, bit for bit, whatever ran before it (no warm start, no time carried
    over), and a new scenario's obstacles reach MuJoCo's model."""
    env = make("paragym/CaPaManCollisionFree-v1")
    try:
        def episode(seed: int) -> list[np.ndarray]:
            out = [env.reset(seed=seed)[0]]
            out += [env.step(np.full(3, 0.5, np.float32))[0] for _ in range(5)]
            return out

        first = episode(5)
        sim = env.unwrapped.world.scene.sim
        geoms = sim.model.ngeom
        episode(9)
        assert sim.model.ngeom != geoms or sim.mirror.recipes["obstacles"] != ()
        for _ in range(2):  # after another scenario (a new model), then after itself (the same model)
            again = episode(5)
            assert all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
        obstacles = [g for g in range(sim.model.ngeom) if sim.model.geom_contype[g] == 1]
        assert len(obstacles) == len(env.unwrapped.world.scene.obstacles) > 0
    finally:
        env.close()


@pytest.mark.parametrize("push", ["down", "sideways"])
def test_the_capaman_stops_at_a_box_in_both_engines(push):
    """The same scene code in both engines: the motors ramp into a box over 1 s and push on for 1 s at their
    torque limit (:func:`paragym.sim.capaman_dynamic.push_into`); the tool stops within 1 mm of where
    PyBullet stops it (1.8 mm with MuJoCo's default contact softness), the loops closed within 0.2 mm, and
    without the box it goes on by more than 5 mm."""
    from paragym.mechanisms import capaman
    from paragym.sim.capaman_dynamic import CaPaManDynamicScene, push_into

    ends = {}
    for engine, box in ((None, True), (MuJoCoSettings(), True), (MuJoCoSettings(), False)):
        scene = CaPaManDynamicScene(capaman.DEFAULT_GEOMETRY, engine=engine)
        try:
            tips, gap = push_into(scene, push, box)
            ends[engine is not None, box] = tips[-1], gap
        finally:
            scene.close()
    (pybullet, _), (blocked, gap), (free, _) = ends[False, True], ends[True, True], ends[True, False]
    assert np.linalg.norm(blocked - pybullet) < 1e-3, (blocked, pybullet)
    assert np.linalg.norm(free - blocked) > 5e-3 and gap < 2e-4, (free, blocked, gap)


def test_the_engine_argument_is_checked(monkeypatch):
    """Each refusal names the argument: an unknown engine, MuJoCo outside the dynamic fidelity or on a task that
    does not run it (every paragym task runs both: here the tripod's told it runs PyBullet only), settings out
    of range, a control period that is not a whole number of MuJoCo's steps."""
    from paragym.tasks import tripod_step

    with pytest.raises(ValueError, match="engine must be"):
        make("paragym/CaPaManCollisionFree-v1", "bullet")
    with pytest.raises(ValueError, match="fidelity='dynamic'"):
        gym.make("paragym/HybridSingularityFree-v2", engine="mujoco")
    with monkeypatch.context() as m:
        m.setattr(tripod_step, "ENGINES", ("pybullet",))
        with pytest.raises(ValueError, match="runs in pybullet only"):
            make("paragym/MobileTripodOdometry-v2")
        make("paragym/MobileTripodOdometry-v2", "pybullet").close()  # the argument is every task's
    with pytest.raises(ValueError, match="time_step"):
        MuJoCoSettings(time_step=0.005)
    with pytest.raises(ValueError, match="servo_bandwidth"):
        MuJoCoSettings(servo_bandwidth=2.0)
    with pytest.raises(ValueError, match="control_period"):
        make("paragym/HybridSingularityFree-v2", MuJoCoSettings(time_step=4e-4), control_period=0.0502)


def test_the_default_engine_is_pybullet():
    """The released ids keep PyBullet: no ``engine`` argument is PyBullet's physics."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("paragym/HybridSingularityFree-v2", fidelity="dynamic")
    try:
        assert env.unwrapped.params.engine is None
        assert isinstance(env.unwrapped.world.scene.sim, PyBulletSim)
    finally:
        env.close()


def test_paragym_validate_runs_in_mujoco(tmp_path, capsys, monkeypatch):
    """``paragym validate ENV --engine mujoco`` validates the reference's episode in MuJoCo and says so in its
    report; an id whose task runs PyBullet only (the tripod's, told so here) is refused, naming the option."""
    import json

    from paragym.cli import main
    from paragym.tasks.tripod_task import TripodTask

    assert main(["validate", "HybridSingularityFree-v2", "--engine", "mujoco", "--out", str(tmp_path)]) == 0
    assert "dynamic fidelity in mujoco" in capsys.readouterr().out
    (report,) = tmp_path.glob("*/report.json")
    assert json.loads(report.read_text())["engine"] == "mujoco"
    monkeypatch.setattr(TripodTask, "engines", ("pybullet",))
    assert main(["validate", "MobileTripodOdometry-v2", "--engine", "mujoco", "--out", str(tmp_path)]) != 0
    assert "--engine mujoco" in capsys.readouterr().err


@pytest.mark.slow
def test_the_leaderboard_runs_the_dynamic_episodes_in_both_engines(tmp_path):
    """A run on an id whose task runs MuJoCo gives each policy its dynamic episodes in both engines, kept apart:
    a MuJoCo column beside PyBullet's in the table and the CSV, the engine in the results file, and
    ``paragym verify`` re-runs the MuJoCo row in MuJoCo; a second run takes both from the database."""
    import csv

    from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
    from paragym.baselines.leaderboard.results import read_results, rows_of_results, verify

    env_id = "paragym/HybridSingularityFree-v2"
    suite = EvalSuite("test", (0,), 1, (("paper", 0),))

    def run():
        return run_leaderboard(tmp_path / "db.sqlite", suite, env_ids=[env_id], policies=["polynomial-detour"],
                               out=tmp_path / "out", progress=False, echo=lambda s: None)

    first = run()
    assert first.new_dynamic == 2
    (summary,) = first.summaries[env_id]
    assert summary.dynamic["success_rate"] == summary.dynamic_mujoco["success_rate"] == 1.0
    assert "MuJoCo" in summary.dynamic_mujoco["settings"] and "MuJoCo" not in summary.dynamic["settings"]
    (written,) = [p for p in first.files if p.name == "results.json.gz"]
    board = (written.parent / "LEADERBOARD.md").read_text()
    assert "MuJoCo: success [95% CI]" in board and "MuJoCo: the same 1 episodes" in board
    (line,) = csv.DictReader((written.parent / "leaderboard.csv").open())
    assert line["mujoco_dynamic_success_rate"] == "1.0000" and line["dynamic_success_rate"] == "1.0000"
    entries = read_results(written)["dynamic"]
    assert sorted("engine" in d for d in entries) == [False, True]
    _, rows = rows_of_results(written)
    assert sorted(r.engine for r in rows) == ["mujoco", "pybullet"]
    checked = verify(written, sample=0, dynamic=2, echo=lambda s: None)
    assert not checked.problems and len(checked.episodes) == 2, checked.problems
    assert all(c.verdict == "identical" for _, c in checked.episodes)
    assert any("in MuJoCo" in what for what, _ in checked.episodes)
    again = run()
    assert (again.new_dynamic, again.skipped_dynamic) == (0, 2)


@pytest.mark.parametrize("env_id, within", [("paragym/CaPaManCollisionFree-v1", 2e-3),
                                             ("paragym/HybridSingularityFree-v2", 1.5)])
@pytest.mark.slow
def test_the_hand_statics_is_what_both_engines_hold(env_id, within):
    """Virtual work on the tree and its loops (paragym.sim.statics) gives the motors' holding forces that each
    engine's motors find after holding the pose for 0.5 s: the CaPaMan's to 2e-3 N m (0.78 N m the largest),
    the hybrid's to 1.5 N (39 N the largest; its platforms sag a little under PyBullet's motors). With gravity
    halved the statics halves, so it is not the engines' numbers read back."""
    from paragym.envs import export as envs_export
    from paragym.sim.client import motors_of
    from paragym.sim.statics import holding_forces

    for engine in (None, MuJoCoSettings()):
        env = envs_export.dynamic_env(env_id)
        try:
            scene = envs_export.scene_of(env)
            statics = holding_forces(scene)
            halved = holding_forces(scene, gravity=scene.dynamics.gravity / 2)
            assert np.allclose(halved, statics / 2, rtol=1e-6, atol=1e-9)
            if engine is not None:
                from paragym.sim.mujoco_sim import simulate_in

                simulate_in(scene, engine)
            scene.hold(0.5)
            held = scene.sim.motor_forces(motors_of([(b, j) for b, j, _ in scene.motor_limits()]))
            assert np.abs(held - statics).max() < within, (engine, held, statics)
        finally:
            env.close()


def test_a_refined_setting_is_the_same_model_on_a_finer_step():
    """What a convergence study sweeps: at half the step and twice the iterations, MuJoCo's servos keep their
    bandwidth in rad/s (a share per step, halved) and PyBullet's motors theirs (the position gain per step,
    halved); the iterations double from the settings' own or, where they name none, the scene's."""
    from paragym.sim.capaman_dynamic import CaPaManDynamics
    from paragym.sim.client import refined

    fine = MuJoCoSettings().refined(0.5, 2, bandwidth=0.25, solver_iterations=100)
    assert fine.time_step == 5e-4 and fine.iterations == 200
    assert fine.servo_bandwidth / fine.time_step == pytest.approx(0.25 / 1e-3)
    own = MuJoCoSettings(servo_bandwidth=0.5, iterations=40).refined(0.25, 4, bandwidth=0.25, solver_iterations=100)
    assert own.iterations == 160 and own.servo_bandwidth / own.time_step == pytest.approx(0.5 / 1e-3)
    d = refined(CaPaManDynamics.split(), 0.5, 2)
    assert (d.time_step, d.solver_iterations, d.position_gain) == (2.5e-3, 200, 0.15)
    assert d.layout == "split" and d.velocity_gain == CaPaManDynamics.split().velocity_gain


@pytest.mark.slow
def test_a_loaded_tripod_unit_stands_still_in_mujoco():
    """Static friction holds in MuJoCo too: a drive unit loaded sideways by 100 N for 2 s with its wheels held
    stays within 0.1 mm, at either preset and at a quarter of the step with four times the iterations. The
    ground's impedance governs its contacts (``solmix``); averaged with a wheel's MuJoCo default, the soft
    contact let the unit slide 0.23-0.26 mm at every one of these settings."""
    pytest.importorskip("mujoco")
    from test_dynamic_fidelity import _creep

    from paragym.sim.tripod_dynamic import TripodDynamics

    converged = TripodDynamics.converged()
    for settings in (MuJoCoSettings(), MuJoCoSettings.fast(), MuJoCoSettings(time_step=2.5e-4, iterations=400)):
        assert _creep(converged, engine=settings) < 1e-4, settings


def test_the_tripod_drives_alike_in_both_engines():
    """The tripod in MuJoCo (its ground, wheels and friction from the exported model, its wheels steered by the
    scene's code): the same spaces, MuJoCo stepping at its 1 ms, and over the paper's 30 s drive with odometry
    alone (the zero action) the units end within 2 cm of where PyBullet puts them (8.3 mm measured) with the
    same unit error within 5 mm."""
    from paragym.sim.tripod_dynamic import TripodDynamics

    env_id = "paragym/MobileTripodOdometry-v2"
    ends = {}
    for engine in ("pybullet", "mujoco"):
        env = make(env_id, engine, scenario=registry.row(env_id).paper_scenario,
                   dynamics=TripodDynamics.converged())
        try:
            env.reset(seed=3)  # the scene is built for the drive's ground
            if engine == "mujoco":
                assert isinstance(env.unwrapped.world.scene.sim, MuJoCoSim)
                assert env.unwrapped.physics_time_step == MuJoCoSettings().time_step
            done = False
            while not done:
                _, _, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, np.float32))
                done = terminated or truncated
            ends[engine] = info["true_units"], info["unit_error"], env.observation_space, env.action_space
        finally:
            env.close()
    (units_pb, error_pb, *spaces_pb), (units_mj, error_mj, *spaces_mj) = ends["pybullet"], ends["mujoco"]
    assert spaces_pb == spaces_mj
    assert np.linalg.norm(units_mj - units_pb, axis=1).max() < 0.02
    assert abs(error_mj - error_pb) < 5e-3


def test_the_tripods_newest_ids_start_on_their_wheels():
    """On a drive whose start puts a unit on a bump's flank (seed 300007), a level chassis at the ground under its
    joint starts its uphill wheel 13.6 mm inside the terrain: MuJoCo's stiff contact launches that unit (v2's start,
    at 0.5 ms), where PyBullet pushes it out. v3 raises each unit onto its wheels, and both engines then settle it
    alike: every unit within 2 cm of where it started after 0.6 s, the legs within 0.01 rad of PyBullet's."""
    settled = {}
    for env_id, engine in (("paragym/MobileTripodOdometry-v2", MuJoCoSettings(time_step=5e-4)),
                           ("paragym/MobileTripodOdometry-v3", MuJoCoSettings(time_step=5e-4)),
                           ("paragym/MobileTripodOdometry-v3", "pybullet")):
        env = make(env_id, engine, scenario="random")
        try:
            env.reset(seed=300007)
            scene = env.unwrapped.world.scene
            start = scene.units_true.copy()
            scene.drive(0.0, 0.6)
            settled[env_id, engine == "pybullet"] = np.linalg.norm(scene.units_true - start, axis=1), scene.eta
        finally:
            env.close()
    assert settled["paragym/MobileTripodOdometry-v2", False][0].max() > 0.2  # launched
    (moved, eta), (_, eta_pybullet) = (settled["paragym/MobileTripodOdometry-v3", k] for k in (False, True))
    assert moved.max() < 0.02 and np.abs(eta - eta_pybullet).max() < 0.01, (moved, eta, eta_pybullet)
