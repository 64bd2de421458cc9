"""``render_mode="human"`` under a virtual display, and what ``rgb_array`` draws in dynamic fidelity.

The PyBullet GUI needs an X server; on a headless machine the tests start
Xvfb (Debian's ``xvfb`` package; ``.ci/run`` installs it when it can) and run
each env in a process of its own, because PyBullet allows one GUI per
process. Gymnasium's ``check_env`` runs with its render check on: it makes
the env in every declared mode, "human" included, resets and renders it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

from paragym import registry

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

#: the newest id of every task, in dynamic fidelity (an older id warns that it is out of date, which the
#: checker's warnings-as-errors would count against it)
CASES = [(registry.rows_of(task)[-1].id, "dynamic") for task in sorted({r.task for r in registry.ROWS})]

_CHECK = """
import sys, warnings
import gymnasium as gym
from gymnasium.utils.env_checker import check_env
import paragym
env_id, fidelity = sys.argv[1], sys.argv[2]
kwargs = {} if fidelity == "kinematic" else {"fidelity": fidelity}
with warnings.catch_warnings():
    warnings.simplefilter("error")
    env = gym.make(env_id, render_mode="human", **kwargs)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample())
        assert env.render() is None
    env.close()
    env = gym.make(env_id, render_mode="rgb_array", **kwargs)
    check_env(env.unwrapped)  # the render check makes, resets and renders a "human" env too
    env.close()
print("ok")
"""


@pytest.fixture(scope="module")
def display():
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        pytest.skip("no display and no Xvfb (apt-get install xvfb) to test render_mode='human'")
    name = f":{90 + os.getpid() % 100}"
    server = subprocess.Popen([xvfb, name, "-screen", "0", "640x480x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.0)
    if server.poll() is not None:
        pytest.skip(f"Xvfb could not start on {name}")
    try:
        yield name
    finally:
        server.terminate()
        server.wait(10)


@pytest.mark.parametrize(("env_id", "fidelity"), CASES)
def test_human_mode_opens_the_gui_and_passes_the_checker_with_its_render_check(display, env_id, fidelity):
    out = subprocess.run([sys.executable, "-c", _CHECK, env_id, fidelity], env={**os.environ, "DISPLAY": display},
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and out.stdout.strip().endswith("ok"), out.stderr[-3000:]


def test_rgb_array_draws_the_simulated_state_not_the_command():
    import gymnasium as gym

    from paragym.sim.hybrid_dynamic import HybridDynamics

    weak = HybridDynamics(motor_force=15.0, time_step=5e-3, solver_iterations=50, erp=0.9)
    env = gym.make("paragym/HybridSingularityFree-v1", scenario="paper", fidelity="dynamic", dynamics=weak,
                   render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(40):
        env.step(np.zeros(4, np.float32))
    drawn = env.render()
    state = env.unwrapped.state
    assert env.unwrapped.world.tracking_error > 0.005  # the weak legs sag: simulated and commanded differ
    scene = env.unwrapped.world.scene
    commanded = state.nominal[0, state.k[0]]
    scene.reset(commanded, float(state.delta[0]))  # pose the commanded state (the zero action: no offset)
    assert np.abs(drawn.astype(int) - env.render().astype(int)).sum() > 0
    env.close()


_DRAWING = """
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Box

sim = PyBulletSim(gui=True)
seen = [sim._drawing]
sim.add_static("box", Box((0.0, 0.0, 0.1), (0.05, 0.05, 0.05)))
seen.append(sim._drawing)
sim.step()
seen.append(sim._drawing)
sim.add_static("box2", Box((0.2, 0.0, 0.1), (0.05, 0.05, 0.05)))
seen.append(sim._drawing)
sim.place("box2", (0.3, 0.0, 0.1), (0.0, 0.0, 0.0, 1.0))
seen.append(sim._drawing)
sim.close()
print(seen)
"""


def test_the_gui_does_not_draw_while_bodies_are_made(display):
    """A GUI that drew after every body made the tripod's first reset take 14 s (2 s without): bodies are made
    with drawing off, and the first step or pose turns it back on."""
    out = subprocess.run([sys.executable, "-c", _DRAWING], env={**os.environ, "DISPLAY": display},
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[False, False, True, False, True]"
