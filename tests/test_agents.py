"""Outside agents: what identifies them (their source, name and parameters), and how they are ranked from a file.

Each test here fails on the producer of paragym 0.8.0, which named a class registered as a factory
``builtins.type`` and hashed no source: an edited agent reused its old rows, and two agents under one name
were mixed."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from paragym.baselines import policies
from paragym.baselines.agents import AgentFile, identity, load_agent
from paragym.baselines.leaderboard import QUICK, run_leaderboard

ENV = "paragym/Orthoglide2PRRKappa-v1"

AGENT = '''
import numpy as np

GAIN = {gain}


class Agent:
    """A constant joint command."""

    env_ids = ["{env}"]

    def __init__(self, env, seed):
        self.shape = env.action_space.shape

    def reset(self, obs, info):
        pass

    def act(self, obs, info):
        return np.full(self.shape, GAIN, np.float32)
'''


def _write(path: Path, gain: float) -> Path:
    path.write_text(AGENT.format(gain=gain, env=ENV))
    return path


@pytest.fixture
def clean_registry():
    saved = {k: dict(v) for k, v in policies._REGISTRY.items()}
    yield
    policies._REGISTRY.clear()
    policies._REGISTRY.update(saved)


def _rank(db: Path, name: str, said: list[str]):
    run = run_leaderboard(db, QUICK, env_ids=[ENV], policies=[name], out=None, validate=False, progress=False,
                          echo=said.append)
    (row,) = run.summaries[ENV]
    return run, row


def test_an_edited_agent_is_run_again(tmp_path: Path, clean_registry: None) -> None:
    path = _write(tmp_path / "mine.py", 0.5)
    name, factory = load_agent(f"{path}:Agent")
    policies.register_policy(ENV, name, factory)
    said: list[str] = []
    first, before = _rank(tmp_path / "db.sqlite", name, said)
    assert first.new_episodes == 3
    _write(path, -0.5)  # a new gain: the same name, the same class, other behaviour
    name, factory = load_agent(f"{path}:Agent")
    policies.register_policy(ENV, name, factory, replace=True)
    said.clear()
    again, after = _rank(tmp_path / "db.sqlite", name, said)
    assert again.new_episodes == 3, "the edited agent's old rows were reused"
    assert any("re-running 3" in line and "source sha256" in line for line in said), said
    assert after.return_mean != before.return_mean
    assert after.producer != before.producer


def test_two_agents_under_one_name_are_never_mixed(tmp_path: Path, clean_registry: None) -> None:
    namespace: dict[str, object] = {}
    exec(compile(AGENT.format(gain=0.5, env=ENV), str(_write(tmp_path / "a.py", 0.5)), "exec"), namespace)
    first_class = namespace["Agent"]

    class Random:  # another agent, registered under the same name
        def __init__(self, env, seed):
            self.space = env.action_space
            self.space.seed(seed)

        def reset(self, obs, info):
            pass

        def act(self, obs, info):
            return self.space.sample()

    policies.register_policy(ENV, "my-agent", first_class)
    _, a = _rank(tmp_path / "db.sqlite", "my-agent", [])
    policies.register_policy(ENV, "my-agent", Random, replace=True)
    run, b = _rank(tmp_path / "db.sqlite", "my-agent", [])
    assert run.new_episodes == 3, "the second agent was given the first one's rows"
    assert json.loads(a.producer)["policy"] != "builtins.type"
    assert a.producer != b.producer and a.return_mean != b.return_mean


def test_what_identifies_an_agent(tmp_path: Path) -> None:
    import functools

    path = _write(tmp_path / "mine.py", 0.5)
    _, factory = load_agent(f"{path}:Agent")
    made = identity(factory)
    assert made["policy"] == "mine.py:Agent" and str(tmp_path) not in json.dumps(made)  # no machine path
    assert len(made["source_sha256"]) == 64

    def gains(env, seed, gain=1.0):
        return None

    assert identity(functools.partial(gains, gain=2.0))["params"] != identity(functools.partial(gains, gain=3.0))[
        "params"]
    # paragym's own policies keep the producers their stored rows were made with
    ref = policies.get_policy(ENV, "gradient-c")
    assert "source_sha256" not in json.loads(ref.producer())


def test_an_agent_without_source_is_never_reused(tmp_path: Path, clean_registry: None) -> None:
    namespace: dict[str, object] = {}
    exec(compile(AGENT.format(gain=0.5, env=ENV), "<stdin>", "exec"), namespace)  # as typed into a REPL
    policies.register_policy(ENV, "typed", namespace["Agent"])
    said: list[str] = []
    _rank(tmp_path / "db.sqlite", "typed", said)
    assert any("source cannot be read" in line for line in said), said
    assert "source" in json.loads(policies.get_policy(ENV, "typed").producer())


def test_agent_file_is_checked_before_it_runs(tmp_path: Path) -> None:
    path = _write(tmp_path / "mine.py", 0.5)
    with pytest.raises(ValueError, match="has no 'Nope'"):
        load_agent(f"{path}:Nope")
    with pytest.raises(ValueError, match="expected path/to/file.py:Factory"):
        load_agent(str(path))
    stale = AgentFile(str(path), "Agent", "0" * 64)
    with pytest.raises(ValueError, match="changed"):
        stale(None, 0)


@pytest.mark.slow
def test_the_guide_ranks_and_verifies_its_agent_file(tmp_path: Path) -> None:
    """docs/guides/own-agent.md: its agent file and its two commands, as a reader would run them."""
    import re
    import shlex

    guide = (Path(__file__).parents[1] / "docs" / "guides" / "own-agent.md").read_text()
    (tmp_path / "my_agent.py").write_text(re.findall(r"^```python\n(.*?)^```", guide, re.S | re.M)[0])
    commands = re.findall(r"^```bash\n(.*?)^```", guide, re.S | re.M)[0].strip().splitlines()
    assert [c.split()[:2] for c in commands] == [["paragym", "leaderboard"], ["paragym", "verify"]]
    for line in commands:
        words = shlex.split(line)
        words = [str(p.relative_to(tmp_path)) for w in words for p in (sorted(tmp_path.glob(w)) or [tmp_path / w])]
        done = subprocess.run([sys.executable, "-m", "paragym.cli", *words[1:], "--no-progress"]
                              if words[1] == "leaderboard" else [sys.executable, "-m", "paragym.cli", *words[1:]],
                              capture_output=True, text=True, timeout=600, cwd=tmp_path)
        assert done.returncode == 0, (line, done.stdout[-2000:], done.stderr[-2000:])
    assert "VERIFIED" in done.stdout and "NOT VERIFIED" not in done.stdout
    table = next((tmp_path / "results" / "mine").rglob("LEADERBOARD.md")).read_text()
    assert "| MyAgent | user |" in table and "A smoke test, not a ranking" in table
