"""``paragym export``: every mechanism as MJCF and URDF, loaded in MuJoCo and PyBullet, its geometry the
kinematics' (issue 41)."""

import json
import warnings

import numpy as np
import pytest

import paragym  # noqa: F401
from paragym import registry
from paragym.envs import export as envs_export
from paragym.sim import export
from paragym.sim.recipes import GROUND

mujoco = pytest.importorskip("mujoco")

NEWEST = list(registry.newest())


@pytest.fixture(scope="module", params=NEWEST)
def env(request):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = envs_export.dynamic_env(request.param)
    yield env
    env.close()


def _both(scene):
    """Both formats' checks at the scene's joint values now."""
    text, sidecar = export.urdf(scene)
    return {"mjcf": export.check_mjcf(scene, export.mjcf(scene)), "urdf": export.check_urdf(scene, text, sidecar)}


def test_the_files_close_the_loops_where_the_kinematics_does(env):
    """At the start of three random scenarios (each reset puts every joint where the task's kinematics has it)
    the exported models' link frames are the simulated tree's and every loop closes, to 1e-9 m, in MuJoCo."""
    for seed in (1, 2, 3):
        env.reset(seed=seed)
        scene = envs_export.scene_of(env)
        for fmt, gaps in _both(scene).items():
            assert gaps["frame_m"] < 1e-9 and gaps["frame_rad"] < 1e-9, (fmt, seed, gaps)
            assert gaps["loop_m"] < 1e-9, (fmt, seed, gaps)
        assert len(json.loads(json.dumps(export.urdf(scene)[1]))["loops"]) == len(scene.sim.loops)


def test_the_open_tree_matches_at_random_joint_values(env):
    """Any joint values, the loops left open: the frames still agree (the tree's geometry alone), while the loop
    gap shows the loops open where the mechanism has any."""
    env.reset(seed=0)
    scene = envs_export.scene_of(env)
    body, links = export.tree_of(scene)
    rng = np.random.default_rng(7)
    for index, link in enumerate(links):
        if link.joint in ("revolute", "prismatic"):
            scene.sim.reset_joint(body, index, float(rng.uniform(-0.3, 0.3)))
        elif link.joint == "spherical":
            q = rng.normal(size=4)
            scene.sim.reset_joint(body, index, list(q / np.linalg.norm(q)))
    for fmt, gaps in _both(scene).items():
        assert gaps["frame_m"] < 1e-9 and gaps["frame_rad"] < 1e-9, (fmt, gaps)
        assert (gaps["loop_m"] > 1e-3) == bool(scene.sim.loops), (fmt, gaps)


def test_a_misplaced_pivot_is_seen(env):
    """The check is not blind: one loop's pivot moved by 1 mm in the MJCF shows as a 1 mm gap."""
    env.reset(seed=0)
    scene = envs_export.scene_of(env)
    if not scene.sim.loops:
        pytest.skip("no loop closure in this mechanism (the tripod's loops close through the ground)")
    text = export.mjcf(scene)
    head, tail = text.split('<site name="loop0_a" pos="', 1)
    x, rest = tail.split(" ", 1)
    moved = f'{head}<site name="loop0_a" pos="{float(x) + 1e-3!r} {rest}'
    assert export.check_mjcf(scene, moved)["loop_m"] == pytest.approx(1e-3, rel=1e-6)


def test_the_urdf_loads_in_pybullet_with_every_joint(env, tmp_path):
    import pybullet as pb

    env.reset(seed=0)
    scene = envs_export.scene_of(env)
    text, sidecar = export.urdf(scene)
    path = tmp_path / "m.urdf"
    path.write_text(text)
    client = pb.connect(pb.DIRECT)
    try:
        robot = pb.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
        names = {pb.getJointInfo(robot, j, physicsClientId=client)[1].decode()
                 for j in range(pb.getNumJoints(robot, physicsClientId=client))}
    finally:
        pb.disconnect(client)
    assert {j for joint in sidecar["joints"] for j in joint["joints"]} <= names
    assert {a["joint"] for a in sidecar["actuators"]} <= names and sidecar["actuators"]


def test_the_mjcf_motors_carry_the_scene_s_force_limits(env):
    env.reset(seed=0)
    scene = envs_export.scene_of(env)
    model = mujoco.MjModel.from_xml_string(export.mjcf(scene))
    limits = sorted(limit for _, _, limit in scene.motor_limits())
    assert model.nu == len(limits)
    assert sorted(model.actuator_forcerange[:, 1]) == limits
    assert np.all(model.actuator_forcerange[:, 0] == -model.actuator_forcerange[:, 1])


def test_export_cli_writes_checks_and_refuses_to_overwrite(tmp_path, capsys):
    from paragym.cli import main

    out = tmp_path / "orthoglide"
    assert main(["export", "Orthoglide2PRRKappa-v2", "--format", "urdf", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert (tmp_path / "orthoglide.urdf").exists() and (tmp_path / "orthoglide.urdf.loops.json").exists()
    assert "loops closed within" in said
    before = (tmp_path / "orthoglide.urdf").read_text()
    (tmp_path / "orthoglide.urdf").write_text("mine")
    capsys.readouterr()
    # an --out that names a file of yours is bad input, as the CLI guide says of it: exit 2, one line
    assert main(["export", "Orthoglide2PRRKappa-v2", "--format", "urdf", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("paragym: error: ") and "--overwrite" in err and err.count("\n") == 1
    assert (tmp_path / "orthoglide.urdf").read_text() == "mine"  # a user's file is not overwritten unasked
    assert main(["export", "Orthoglide2PRRKappa-v2", "--format", "urdf", "--out", str(out), "--overwrite"]) == 0
    assert (tmp_path / "orthoglide.urdf").read_text() == before
    assert main(["export", "Orthoglide2PRRKappa-v2", "--out", str(tmp_path / "models") + "/"]) == 0  # a folder
    assert (tmp_path / "models" / "Orthoglide2PRRKappa-v2.xml").exists()
    assert not (tmp_path / "models.xml").exists()


@pytest.mark.parametrize("push", ["down", "sideways"])
def test_the_exported_capaman_stops_at_a_box_where_pybullet_does(push):
    """Contact in both engines: the CaPaMan's motors ramp into a box over 1 s and push on for 1 s at their torque
    limit (``tests/test_rules.py``'s pushes); in MuJoCo, from the exported MJCF with the box as a fixed geom, the
    tool stops within 2.5 mm of where PyBullet stops it (without the box it goes on by more than 5 mm), and the
    loops stay closed within 0.2 mm."""
    from test_rules import HOME, PUSHES

    from paragym.mechanisms import capaman
    from paragym.sim.capaman_dynamic import CaPaManDynamicScene

    box, goal = PUSHES[push]
    ends = {}
    for obstacles in ((box,), ()):
        scene = CaPaManDynamicScene(capaman.DEFAULT_GEOMETRY)
        try:
            scene.set_obstacles(obstacles)
            scene.set_configuration(HOME)
            body, links = export.tree_of(scene)
            values = scene.sim.joint_values(body)
            model = mujoco.MjModel.from_xml_string(export.mjcf(scene))
            if obstacles:
                for i in range(100):  # as tests/test_rules.py's _push
                    scene.drive(HOME + (goal - HOME) * min(1.0, (i + 1) / 50), 0.02)
                pybullet_tool = scene.sim.link_frame(body, "tool")[0]
        finally:
            scene.close()
        data = export.mujoco_pose(model, links, values, urdf=False)
        start = export.mujoco_motor_positions(model, data)
        ramp, gap = int(round(1.0 / model.opt.timestep)), 0.0
        for i in range(2 * ramp):
            data.ctrl[:] = start + (-goal - start) * min(1.0, (i + 1) / ramp)  # the crank joints turn by -alpha
            mujoco.mj_step(model, data)
            gap = max(gap, export.mujoco_loop_gap(model, data))
        ends[bool(obstacles)] = data.body("tool").xpos.copy(), gap
    (blocked, gap), (free, _) = ends[True], ends[False]
    assert np.linalg.norm(blocked - pybullet_tool) < 2.5e-3, (blocked, pybullet_tool)
    assert np.linalg.norm(free - blocked) > 5e-3 and gap < 2e-4, (free, blocked, gap)


#: run with MuJoCo and numpy alone: load a model file, step it 1 s under gravity from MjData's start (qpos0,
#: ctrl zero), and report its loops' widest gap and how far its bodies moved, in all and in the last half second
STANDALONE = r"""
import json, sys
import mujoco
import numpy as np

model = mujoco.MjModel.from_xml_path(sys.argv[1])
data = mujoco.MjData(model)
mujoco.mj_forward(model, data)

def gap():
    if not model.neq:
        return 0.0
    d = data.site_xpos[model.eq_obj1id] - data.site_xpos[model.eq_obj2id]
    return float(np.sqrt((d ** 2).sum(axis=1)).max())

start, loops, steps = data.xpos.copy(), gap(), int(round(1.0 / model.opt.timestep))
for step in range(steps):
    mujoco.mj_step(model, data)
    loops = max(loops, gap())
    if step + 1 == steps // 2:
        half = data.xpos.copy()
home = np.asarray(model.key("home").qpos) - model.qpos0
print(json.dumps({"loops_m": loops, "moved_m": float(np.abs(data.xpos - start).max()),
                  "late_m": float(np.abs(data.xpos - half).max()), "finite": bool(np.isfinite(data.qpos).all()),
                  "home_is_qpos0": float(np.abs(home).max()), "time": data.time,
                  "paragym": any(name.startswith("paragym") for name in sys.modules)}))
"""


@pytest.mark.parametrize("env_id", NEWEST)
def test_an_exported_mjcf_simulates_on_its_own(env_id, tmp_path):
    """``paragym export`` writes a model that MuJoCo alone (no paragym import) steps for 1 s under gravity from
    ``MjData``'s start, which is the ``home`` keyframe: the loops stay closed within 0.1 mm, no body moves more
    than 1.5 cm (the tripod's units settle onto their casters, 1 cm clear of the ground), and in the last half
    second none moves more than 0.5 mm (no creep, no drift of the servos). Written at joint values of zero
    (before issue 52) the CaPaMan's loops started 0.128 m open and the model went unstable at 13 ms."""
    import subprocess
    import sys

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (path,), gaps = envs_export.write(env_id, "mjcf", tmp_path)  # a folder: the file is named after the env
    assert path == tmp_path / (env_id.split("/")[1] + ".xml")
    assert max(gaps.values()) < 1e-9, gaps
    got = json.loads(subprocess.run([sys.executable, "-c", STANDALONE, str(path)], capture_output=True, text=True,
                                    check=True, cwd=tmp_path).stdout)
    assert not got["paragym"] and got["finite"] and got["time"] == pytest.approx(1.0), got
    assert got["home_is_qpos0"] == 0.0, got
    assert got["loops_m"] < 1e-4, got
    assert got["moved_m"] < 0.015 and got["late_m"] < 5e-4, got


def test_the_urdf_sidecar_s_home_closes_the_loops(env):
    """The URDF's sidecar names a pose for every joint (``home``) at which its loops close: posed from the
    sidecar alone, in MuJoCo's URDF importer, each closure's two points meet within 1e-9 m."""
    env.reset(seed=0)
    scene = envs_export.scene_of(env)
    text, sidecar = export.urdf(scene)
    keep = '<mujoco><compiler fusestatic="false" discardvisual="true"/></mujoco>'
    model = mujoco.MjModel.from_xml_string(text.replace(">", ">" + keep, 1))
    data = mujoco.MjData(model)
    assert set(sidecar["home"]) == {model.joint(j).name for j in range(model.njnt)}  # every moving joint
    for name, value in sidecar["home"].items():
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)

    def point(link, at):
        if link == "base":
            return np.asarray(at)
        b = model.body(link).id
        return data.xpos[b] + data.xmat[b].reshape(3, 3) @ np.asarray(at)

    for loop in sidecar["loops"]:
        assert np.linalg.norm(point(loop["link_a"], loop["point_a"]) - point(loop["link_b"], loop["point_b"])) < 1e-9
    grounds = [name for name, recipe in scene.sim.recipes.items() if isinstance(recipe, GROUND)]
    assert len(sidecar["missing"]) == len(grounds)  # what URDF cannot hold is named (the tripod's ground)
