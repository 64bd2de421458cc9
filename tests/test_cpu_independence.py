"""Numbers that do not depend on the CPU (issue 38): the parts of an episode paragym computes itself give the
same bits with another CPU's BLAS kernels and numba's generic target, simulated here by making each library
take another CPU's code in a new process (:data:`paragym.machine.SIMULATED`). numpy's AVX-512 loops for a few
functions (arctan2, arcsin, arccos) and glibc's libm variants still round differently: ``paragym verify``'s
tolerance covers them (``docs/reports/cpu.md``)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from paragym import machine

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

#: the learned actors of two shipped models, one per kind of network (Tanh actor-critic; ReLU and squashed SAC),
#: on 300 observations drawn in their spaces: the hash of the actions
ACTORS = """
import hashlib, numpy as np
from paragym.baselines.policies import policies_for
out = hashlib.sha256()
for env_id, name in (("paragym/CaPaManCollisionFree-v1", "ppo-seed0"), ("paragym/Orthoglide2PRRKappa-v0", "sac-seed0"),
                     ("paragym/MobileTripodOdometry-v1", "bc-seed0")):
    spec = policies_for(env_id)[name]
    import gymnasium as gym
    env = gym.make(env_id)
    policy = spec.factory(env, 0)
    rng = np.random.default_rng(0)
    space = env.observation_space
    for _ in range(300):
        obs = rng.uniform(np.maximum(space.low, -3), np.minimum(space.high, 3)).astype(np.float32)
        out.update(np.asarray(policy.act(obs, {}), np.float32).tobytes())
    env.close()
print(out.hexdigest())
"""

#: the hybrid's two singularity measures on 2,000 poses near home, and along 60 steps of the env
HYBRID = """
import hashlib, numpy as np, gymnasium as gym
import paragym
from paragym.mechanisms import hybrid
rng = np.random.default_rng(0)
p = rng.normal(0, [0.03, 0.03, 0.03, 0.15, 0.15, 0.15], (2000, 6))
lengths, mu_h, mu_t, *_ = hybrid.solve_rows(p, rng.uniform(0, 1, 2000))
env = gym.make("paragym/HybridSingularityFree-v2")
env.reset(seed=0)
steps = []
for _ in range(60):
    _, _, te, tr, info = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
    steps += [info["mu_hexapod"], info["mu_tripod"]]
    if te or tr:
        env.reset()
print(hashlib.sha256(np.concatenate([mu_h, mu_t, steps]).tobytes()).hexdigest())
"""


#: the tripod's rigid fit on 1,000 configurations, and 120 steps of its dynamic fidelity (a chaotic drive, in
#: which a last-bit difference grows: 0.9.0's BLAS products moved its final unit error by centimetres)
TRIPOD = """
import hashlib, numpy as np, gymnasium as gym
import paragym
from paragym.mechanisms import tripod as mt

rng = np.random.default_rng(0)
local = rng.normal(size=(1000, 3, 3))
rot, shift = mt.plate_fit(local, rng.uniform(0.5, 1.0, (1000, 3)))
env = gym.make("paragym/MobileTripodOdometry-v2", fidelity="dynamic")
obs, _ = env.reset(seed=3)
steps = [obs]
for _ in range(120):
    obs, _, te, tr, info = env.step(np.zeros(env.action_space.shape, np.float32))
    steps += [obs, np.array([info["unit_error"]])]
    if te or tr:
        break
print(hashlib.sha256(np.concatenate([rot.ravel(), shift.ravel(), *[np.ravel(x) for x in steps]]).tobytes()).hexdigest())
"""


def _digest(code: str, cpu: str) -> str:
    done = subprocess.run([sys.executable, "-c", code], env=machine.simulated_environment(cpu), capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout.strip().splitlines()[-1]


@pytest.mark.parametrize("what", ["actors", "hybrid", "tripod"])
def test_the_same_bits_on_another_cpu(what: str) -> None:
    code = {"actors": ACTORS, "hybrid": HYBRID, "tripod": TRIPOD}[what]
    here = _digest(code, "host")
    for cpu in ("older-blas-generic-numba", "avx512-blas"):
        assert _digest(code, cpu) == here, f"{what} differ on the simulated {cpu}"


def test_the_simulation_changes_what_it_says() -> None:
    """The simulated CPU does change the libraries' code: BLAS products of the same numbers differ."""
    code = ("import numpy as np, hashlib; r = np.random.default_rng(0); a = r.normal(size=(64, 300)); "
            "b = r.normal(size=300); print(hashlib.sha256((a @ b).tobytes()).hexdigest())")
    assert _digest(code, "older-x86-64") != _digest(code, "avx512-blas")


def test_describe_names_what_results_depend_on() -> None:
    facts = machine.describe()
    assert facts["cpu"]["model"] and facts["cpu"]["isa"]["found"]
    assert facts["blas"] and facts["blas"][0]["architecture"]
    assert facts["numba"]["cpu_name"]
    with pytest.raises(ValueError, match="unknown simulated CPU"):
        machine.simulated_environment("pentium")


def test_the_deterministic_tanh_is_tanh() -> None:
    from paragym.baselines.actor import k_tanh

    x = np.concatenate([np.linspace(-30, 30, 200_001), [0.0, -0.0, 1e-30, -1e-12, 20.0, 400.0, -400.0]])
    got = np.array([k_tanh(v) for v in x])
    np.testing.assert_allclose(got, np.tanh(x), rtol=1e-15, atol=1e-300)
    assert np.all(np.abs(got) <= 1.0) and got[-3] == 1.0 and got[-1] == -1.0


def test_a_kernel_cache_older_than_its_sources_is_cleared(tmp_path) -> None:
    """numba keys a cached kernel on its own file only: after a callee's file changes, the caller's cache would
    run the old callee. Any change to a source that uses numba clears the caches; an unchanged tree keeps them."""
    core, other = tmp_path / "core", tmp_path / "other"
    for folder, name in ((core, "callee.py"), (other, "caller.py")):
        (folder / "__pycache__").mkdir(parents=True)
        (folder / name).write_text("from numba import njit\n")
        (folder / "__pycache__" / f"{name[:-3]}.k-1.py311.nbi").write_bytes(b"index")
        (folder / "__pycache__" / f"{name[:-3]}.k-1.py311.1.nbc").write_bytes(b"code")
    (core / "plain.py").write_text("x = 1\n")
    caches = lambda: sorted(p.name for p in tmp_path.rglob("*.nb?"))  # noqa: E731
    assert machine.refresh_kernel_cache([core, other]) and caches() == []  # no digest yet: cleared
    (other / "__pycache__" / "caller.k-1.py311.nbi").write_bytes(b"index")
    assert not machine.refresh_kernel_cache([core, other]) and caches() == ["caller.k-1.py311.nbi"]
    (core / "plain.py").write_text("x = 2\n")  # no kernel there: the caches stand
    assert not machine.refresh_kernel_cache([core, other]) and caches() == ["caller.k-1.py311.nbi"]
    (core / "callee.py").write_text("from numba import njit\n# changed\n")
    assert machine.refresh_kernel_cache([core, other]) and caches() == []
