"""End-to-end PPO training speed on the native vector envs: Stable-Baselines3 beside the other learners.

For each env id (default: the newest version of every task), each learner
trains PPO from scratch on ``gym.make_vec(ID, N, "vector_entry_point")``
behind SB3's VecEnv interface (:mod:`paragym.baselines.sb3_vec`), with the
same settings for all: the env's PPO row of ``baselines/hyperparams/ppo.yml``
(n_steps, n_epochs, gamma, gae_lambda, learning rate, clip range, the
policy's layers), N robots and minibatches of ``N * n_steps / 4``. A warm-up
``learn`` first (numba's kernels load, JAX compiles), then ``--timesteps``
steps are timed. The figure is env steps per second of ``model.learn``,
collection and updates together, its ratio to SB3's in the same run, and
the share of the time in the updates (``model.train``).

Learners (each measured only when installed):

* ``sb3``: Stable-Baselines3's PyTorch PPO, ``torch.set_num_threads(--threads)``;
* ``sbx``: SBX (``sbx-rl``), Stable-Baselines3's API on JAX/Flax, on JAX's CPU backend;
* ``torchrl``: TorchRL's PPO parts (``Collector``, ``GAE``, ``ClipPPOLoss``, a replay buffer sampled
  without replacement) in the loop of its PPO tutorial, on the native env's SAME_STEP view
  (:class:`paragym.envs.vector.SameStepVectorEnv`, which SB3's adapter also steps) through
  ``GymWrapper``, which takes gymnasium vector envs with same-step autoreset only; a Gaussian
  policy with a state-independent scale, SB3's loss weights (value 0.5, gradients clipped at 0.5) and
  Adam's epsilon 1e-5.

PufferLib is not measured: 3.0.0 is a source package whose build downloads raylib from the internet, and
2.0.2, the newest wheel, pins numpy 1.23 and gymnasium <= 0.29 and does not ship its PPO trainer.

    python benchmarks/learner_speed.py [--env ID ...] [--robots 64] [--timesteps 32768]
"""

from __future__ import annotations

import argparse
import importlib.util
import time
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
from results_file import add_record_option, record  # this folder is on the path when it runs

import paragym
from paragym.baselines.sb3_vec import as_sb3_vecenv
from paragym.baselines.training import console_logger, load_hyperparams
from paragym.envs.vector import SameStepVectorEnv
from paragym.registry import check_env_id, newest

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "PPO trained side by side with Stable-Baselines3 (PyTorch), SBX (JAX) and TorchRL on each native env "
    "with 64 robots and the same settings: env steps/s of the whole learning loop (32,768 timed steps "
    "after a warm-up) and the share of the time in the updates (sbx-rl 0.28.0, JAX 0.10.2, torchrl "
    "0.14.1, PyTorch 2.13.0 with two threads). "
)

#: the settings every learner gets from an env's PPO row
SHARED = ("n_steps", "n_epochs", "gamma", "gae_lambda", "learning_rate", "clip_range", "ent_coef")


def settings(env_id: str, robots: int) -> dict[str, Any]:
    """The PPO keyword arguments every learner gets (module docstring)."""
    hp = load_hyperparams("ppo", env_id)
    kwargs = {k: hp[k] for k in SHARED if k in hp}
    kwargs["batch_size"] = robots * int(kwargs["n_steps"]) // 4
    arch = (hp.get("policy_kwargs") or {}).get("net_arch", [64, 64])
    kwargs["policy_kwargs"] = {"net_arch": list(arch)}
    return kwargs


def learner(name: str, threads: int) -> Any:
    """The PPO class of a learner (None when it is not installed)."""
    if name == "sb3":
        import torch
        from stable_baselines3 import PPO

        torch.set_num_threads(threads)
        return PPO
    if name == "sbx":
        if importlib.util.find_spec("sbx") is None:
            return None
        from sbx import PPO

        return PPO
    raise ValueError(f"learner must be sb3 or sbx; got {name!r}")


def torchrl_steps_per_second(env_id: str, robots: int, timesteps: int, threads: int
                             ) -> tuple[float, float, float] | None:
    """:func:`steps_per_second` for TorchRL's PPO (module docstring); None when TorchRL is not installed."""
    if importlib.util.find_spec("torchrl") is None:
        return None
    import torch
    from tensordict.nn import AddStateIndependentNormalScale, TensorDictModule
    from torchrl.collectors import Collector
    from torchrl.data import LazyTensorStorage, ReplayBuffer, SamplerWithoutReplacement
    from torchrl.envs.libs.gym import GymWrapper
    from torchrl.modules import MLP, IndependentNormal, ProbabilisticActor, ValueOperator
    from torchrl.objectives import ClipPPOLoss
    from torchrl.objectives.value import GAE

    torch.set_num_threads(threads)
    torch.manual_seed(0)
    kw = settings(env_id, robots)
    arch = kw["policy_kwargs"]["net_arch"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = GymWrapper(SameStepVectorEnv(gym.make_vec(env_id, num_envs=robots,
                                                        vectorization_mode="vector_entry_point")))
        n_obs, n_act = env.observation_spec["observation"].shape[-1], env.action_spec.shape[-1]
        actor = ProbabilisticActor(
            TensorDictModule(torch.nn.Sequential(MLP(n_obs, n_act, num_cells=arch, activation_class=torch.nn.Tanh),
                                                 AddStateIndependentNormalScale(n_act)),
                             in_keys=["observation"], out_keys=["loc", "scale"]),
            in_keys=["loc", "scale"], spec=env.action_spec, distribution_class=IndependentNormal,
            return_log_prob=True)
        critic = ValueOperator(MLP(n_obs, 1, num_cells=arch, activation_class=torch.nn.Tanh), in_keys=["observation"])
        rollout = robots * int(kw["n_steps"])
        total = rollout * (1 + -(-max(timesteps, rollout) // rollout))
        collector = Collector(env, actor, frames_per_batch=rollout, total_frames=total)
        gae = GAE(gamma=kw["gamma"], lmbda=kw["gae_lambda"], value_network=critic, average_gae=False)
        loss = ClipPPOLoss(actor, critic, clip_epsilon=kw["clip_range"], entropy_coeff=kw.get("ent_coef", 0.0),
                           critic_coeff=0.5, loss_critic_type="l2", normalize_advantage=True)
        optim = torch.optim.Adam(loss.parameters(), lr=kw["learning_rate"], eps=1e-5)
        buffer = ReplayBuffer(storage=LazyTensorStorage(rollout), sampler=SamplerWithoutReplacement(),
                              batch_size=kw["batch_size"])
        clock = {"train": 0.0, "collect": 0.0}
        steps, t0, mark = 0, 0.0, time.perf_counter()
        for batch, data in enumerate(collector):
            now = time.perf_counter()
            clock["collect"] += now - mark
            with torch.no_grad():
                gae(data)
            buffer.extend(data.reshape(-1))
            for _ in range(int(kw["n_epochs"])):
                for _ in range(rollout // kw["batch_size"]):
                    out = loss(buffer.sample())
                    (out["loss_objective"] + out["loss_critic"] + out.get("loss_entropy", 0.0)).backward()
                    torch.nn.utils.clip_grad_norm_(loss.parameters(), 0.5)
                    optim.step()
                    optim.zero_grad()
            collector.update_policy_weights_()
            mark = time.perf_counter()
            clock["train"] += mark - now
            if batch == 0:  # the first rollout and its update were the warm-up: the clock starts now
                t0, clock = mark, {"train": 0.0, "collect": 0.0}
            else:
                steps += rollout
        seconds = mark - t0
        collector.shutdown()
    env.close()
    return steps / seconds, clock["train"] / seconds, steps / clock["collect"]


def measure(name: str, env_id: str, robots: int, timesteps: int, threads: int) -> tuple[float, float, float] | None:
    """What :func:`steps_per_second` gives for learner ``name`` (module docstring); None when it is not installed."""
    if name == "torchrl":
        return torchrl_steps_per_second(env_id, robots, timesteps, threads)
    cls = learner(name, threads)
    return None if cls is None else steps_per_second(cls, env_id, robots, timesteps)


def _timed(model: Any, name: str, clock: dict[str, float]) -> None:
    """Add the time of each call of ``model.<name>`` to ``clock[name]``."""
    method = getattr(model, name)

    def timed(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            clock[name] += time.perf_counter() - t0

    setattr(model, name, timed)


def steps_per_second(cls: Any, env_id: str, robots: int, timesteps: int) -> tuple[float, float, float]:
    """Env steps/s of ``cls``'s PPO learning ``timesteps`` steps on ``robots`` robots, after a warm-up; the
    share of that time in the updates (``model.train``); and the steps/s of the collection alone
    (``model.collect_rollouts``: the env stepped by the policy's inference)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = as_sb3_vecenv(env_id, robots)
        model = cls("MlpPolicy", env, seed=0, device="cpu", verbose=0, **settings(env_id, robots))
        model.set_logger(console_logger())
        rollout = robots * model.n_steps
        model.learn(rollout)  # warm-up: kernels load, JAX compiles its update
        clock = {"train": 0.0, "collect_rollouts": 0.0}
        _timed(model, "train", clock)
        _timed(model, "collect_rollouts", clock)
        start, t0 = model.num_timesteps, time.perf_counter()
        model.learn(max(timesteps, rollout), reset_num_timesteps=False)
        seconds = time.perf_counter() - t0
    env.close()
    steps = model.num_timesteps - start
    return steps / seconds, clock["train"] / seconds, steps / clock["collect_rollouts"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", help="only this env id (repeatable; the 'paragym/' may be omitted)")
    parser.add_argument("--robots", type=int, default=64, help="N robots of the native env (default %(default)s)")
    parser.add_argument("--timesteps", type=int, default=32_768, help="timed steps per learner (default %(default)s)")
    parser.add_argument("--threads", type=int, default=2, help="PyTorch's threads (default %(default)s)")
    parser.add_argument("--learner", action="append", choices=("sb3", "sbx", "torchrl"),
                        help="only these (repeatable)")
    add_record_option(parser)
    args = parser.parse_args()
    ids = [check_env_id(e) for e in args.env] if args.env else [e for e in newest() if e in paragym.VECTOR_ENTRY_POINTS]
    names = args.learner or ["sb3", "sbx", "torchrl"]
    rows = []
    for env_id in ids:
        rates: dict[str, float | None] = {}
        shares: dict[str, float] = {}
        for name in names:
            measured = measure(name, env_id, args.robots, args.timesteps, args.threads)
            if measured is None:
                rates[name] = None
                print(f"{env_id} {name}: not installed", flush=True)
                continue
            rates[name], shares[name], _ = measured
            print(f"{env_id} {name}: {rates[name]:,.0f} steps/s, {100 * shares[name]:.0f} % of it in the updates",
                  flush=True)
        rows.append((env_id, rates, shares))
    print(f"\nPPO, {args.robots} robots, {args.timesteps:,} timed steps; env steps/s of model.learn and x SB3's")
    print(f"{'environment':34s}" + "".join(f"{n:>12s}{'x sb3':>8s}{'update':>8s}" for n in names))
    table = []
    for env_id, rates, shares in rows:
        base = rates.get("sb3")
        table.append([env_id.split("/")[-1]] + [c for n in names for c in (
            ["-", "-", "-"] if rates[n] is None else
            [f"{rates[n]:,.0f}", f"{rates[n] / base:.1f}" if base else "-", f"{100 * shares[n]:.0f} %"])])
        cells = []
        for n in names:
            rate = rates[n]
            cells.append(f"{'-':>12s}{'-':>8s}{'-':>8s}" if rate is None else
                         f"{rate:12,.0f}" + (f"{rate / base:8.1f}" if base else f"{'-':>8s}")
                         + f"{100 * shares[n]:7.0f}%")
        print(f"{env_id.split('/')[-1]:34s}" + "".join(cells))
    if any(np.isnan(r) for _, rates, _ in rows for r in rates.values() if r is not None):
        raise SystemExit("a rate is NaN")
    if args.record:
        record("learner_speed", "The learner: PPO in Stable-Baselines3, SBX and TorchRL", PARAGRAPH,
               ["environment"] + [c for n in names for c in (f"{n} PPO (steps/s)", "x SB3", "its updates")], table,
               order=50, folder=args.record)


if __name__ == "__main__":
    main()
