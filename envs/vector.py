"""The base of paragym's native vector environments: N robots per numpy call.

``gymnasium.make_vec(ENV_ID, num_envs=N, vectorization_mode="vector_entry_point")``
returns one of these. It runs the same task as the single env, with the same
numbers: for the same seeds its observations, rewards, terminations and
truncations equal those of ``SyncVectorEnv`` over single envs (to 1e-9,
tested for every task). Each robot keeps its own ``np.random.Generator``
seeded as the single env seeds its own (``reset(seed=s)`` gives robot i the
seed ``s + i``, as gymnasium's vector envs do), and draws from it in the same
order, so scenarios and noise agree.

Autoreset: gymnasium 1.x's ``NEXT_STEP`` mode, as ``SyncVectorEnv``: the step
after a robot's episode ends resets that robot (its action is ignored; its
reward is 0 and its termination and truncation flags are False). The time
limit of the registration (``max_episode_steps``) truncates as ``TimeLimit``.
:class:`SameStepVectorEnv` gives the ``SAME_STEP`` view of the same env, which
Stable-Baselines3 (:mod:`paragym.baselines.sb3_vec`) and TorchRL's
``GymWrapper`` expect.

The single env and the vector env of a task are shells over one
contract, written once over N robots (:class:`paragym.tasks.base.Task`): the
single env is its N = 1 case, so the numbers agree because the code is the
same. The vector env builds no single env: it checks its keyword arguments
with the task's ``Params.from_kwargs`` as the single env does, and its info
holds the numbers, success and failure of :meth:`Task.evaluate`, the one
place a task decides them. A reset draws each resetting robot's random numbers from its own
generator (the draws stay per robot to match the single env); the tests
that accept or reject a drawn scenario then run for all of them at once
where the task allows (Orthoglide, hybrid).
PyBullet stays the renderer: ``render()`` draws robot ``render_index`` as the
single env draws its robot.
"""

from __future__ import annotations

import inspect
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from paragym.envs.base import (
    TaskShell,
    box,
    check_action,
    check_options,
    check_seed,
    check_train_scenarios,
    env_signature,
)
from paragym.tasks.base import Task

__all__ = ["ParagymVectorEnv", "SameStepVectorEnv"]


class ParagymVectorEnv(TaskShell, VectorEnv):
    """N robots of a task in one call: a generic shell over the task's contract.

    A subclass per env id sets :attr:`task` and :attr:`rules`, as the single env's class does (the two share
    them); ``reset`` and ``step`` call the task's ``draw_scenarios``, ``reset``, ``step`` and ``evaluate``
    over the robots that reset or step, and read the observations, rewards and terminations from
    ``self.state`` (the task's state of N robots). Keyword arguments are the single env's; the fidelities
    the native vector env runs are the task's ``vector_fidelities``.

    Lifecycle: as the single env's, with ``reset_mask`` an option besides ``scenario``; an ended robot is
    reset by the next step (autoreset), not refused.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": ["rgb_array"]}

    #: the task and this id's rules, the single env's
    task: ClassVar[Task[Any, Any, Any, Any]]
    rules: ClassVar[Any]
    __signature__: ClassVar[inspect.Signature]
    single_action_space: Box
    single_observation_space: Box

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "task" in cls.__dict__:
            own = [inspect.Parameter("num_envs", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation="int"),
                   *(inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=d)
                     for n, d in (("max_episode_steps", None), ("render_index", 0)))]
            cls.__signature__ = env_signature(cls.task, tuple(own))

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 render_mode: str | None = None, train_scenarios: int | None = None, **kwargs: Any) -> None:
        if not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer; got {num_envs!r}")
        if not 0 <= render_index < num_envs:
            raise ValueError(f"render_index must lie in [0, {num_envs - 1}]; got {render_index!r}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be 'rgb_array' or None; got {render_mode!r}")
        self.num_envs = int(num_envs)
        self.train_scenarios = check_train_scenarios(train_scenarios)
        self.params = self.task.vector_params(self.rules, kwargs)
        self.render_mode = render_mode
        self.render_index = int(render_index)
        self.single_observation_space, self.single_action_space = (box(b) for b in self.task.spaces(self.params))
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.max_episode_steps = max_episode_steps
        #: each robot's generator: seeded by a reset's seed, else from the OS's entropy (as gymnasium's envs)
        self._rngs = [seeding.np_random()[0] for _ in range(self.num_envs)]
        self.state = self.task.State.empty(self.num_envs, self.params)
        self.world = self.task.make_world(self.params, self.num_envs, render_mode)
        self._render: dict[str, Any] = {}
        self._evaluation: Any = None
        self._elapsed = np.zeros(self.num_envs, np.int64)
        self._autoreset = np.zeros(self.num_envs, bool)
        self._started = False
        self._closed = False
        self._failure_names = np.array(self.task.failures, dtype=object)

    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        """Draw, check and start the scenarios of robots ``rows`` (one generator each); return them."""
        task, p = self.task, self.params
        scenarios = self.draw(options.get("scenario", p.scenario), rngs)
        task.reset(self.state, p, rows, scenarios, rngs, self.world)
        return scenarios

    # --- the loop ---------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every robot, or those of ``options["reset_mask"]`` (a boolean
        array of ``num_envs``, as gymnasium's vector envs take it). Every
        argument is checked before any robot changes: a bad seed list or mask
        leaves the env as it was."""
        self._check_open()
        options = check_options(options, ("scenario", "reset_mask"))
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            check_seed(seed)
            seeds = [int(seed) + i for i in range(self.num_envs)]
        elif isinstance(seed, list | tuple | np.ndarray):
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed must be an int, None or a list of {self.num_envs} seeds; got {len(seeds)}")
            seeds = [check_seed(s, f"seed[{i}]") for i, s in enumerate(seeds)]
        else:
            raise TypeError(f"seed must be an int, None or a list of {self.num_envs} seeds; got {seed!r}")
        mask = np.ones(self.num_envs, bool)
        if "reset_mask" in options:
            mask = options.pop("reset_mask")
            if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_ or mask.shape != (self.num_envs,):
                raise TypeError(f"options['reset_mask'] must be a boolean numpy array of shape ({self.num_envs},); "
                                f"got {mask!r:.80}")
            if not mask.any():
                raise ValueError("options['reset_mask'] must be true for at least one robot")
            if not self._started and not mask.all():
                raise ValueError("the first reset resets every robot: leave out options['reset_mask']")
        rows = np.flatnonzero(mask)
        saved = [self._rngs[i] for i in rows]
        for i in rows:
            if seeds[i] is not None:
                self._rngs[i], _ = seeding.np_random(seeds[i])
        try:
            self._start(rows, [self._rngs[i] for i in rows], options)
        except BaseException:
            for i, rng in zip(rows, saved, strict=True):  # a refused scenario leaves the generators as they were
                self._rngs[i] = rng
            raise
        self._evaluation = self.task.evaluate(self.state, self.params, self.world)
        self._elapsed[rows] = 0
        self._autoreset[rows] = False
        self._started = True
        return self.state.obs.copy(), self._infos()

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if self._closed:
            self._check_open()
        if not self._started:
            raise RuntimeError("call reset() before step()")
        actions = check_action(actions, self.single_action_space, "actions", rows=self.num_envs)
        resetting = np.flatnonzero(self._autoreset)
        active = ~self._autoreset
        self.task.step(self.state, self.params, actions, active, self.world)
        if resetting.size:
            self._start(resetting, [self._rngs[i] for i in resetting], {})
        self._evaluation = self.task.evaluate(self.state, self.params, self.world)
        s = self.state
        obs, reward, terminated = s.obs.copy(), s.reward.copy(), s.terminated.copy()
        self._elapsed += active
        self._elapsed[resetting] = 0
        truncated = (self._elapsed >= self.max_episode_steps if self.max_episode_steps is not None
                     else np.zeros(self.num_envs, bool))
        reward[resetting] = 0.0
        terminated[resetting] = False
        truncated[resetting] = False
        self._autoreset = terminated | truncated
        return obs, reward, terminated, truncated, self._infos()

    def reset_done(self) -> tuple[np.ndarray, np.ndarray]:
        """Reset now the robots whose episode ended at the last step (instead
        of at the next one): gymnasium's SAME_STEP view, which Stable-Baselines3
        expects. Returns their indices and their first observations."""
        rows = np.flatnonzero(self._autoreset)
        if rows.size:
            self._start(rows, [self._rngs[i] for i in rows], {})
            self._evaluation = self.task.evaluate(self.state, self.params, self.world)
            self._elapsed[rows] = 0
            self._autoreset[rows] = False
        return rows, self.state.obs[rows].copy()

    def render(self) -> np.ndarray | None:  # type: ignore[override]  # one robot's frame, not one per robot
        """Robot ``render_index`` drawn by PyBullet (``render_mode="rgb_array"``): one frame (gymnasium's
        vector envs give a tuple of every env's)."""
        if self.render_mode != "rgb_array" or not self._started:
            return None
        return self.task.render(self._render, self.state, self.params, self.world, self.render_index, False)

    def close_extras(self, **kwargs: Any) -> None:
        self._close_all()

    def _infos(self) -> dict[str, Any]:
        """Gymnasium's vector info dict: the task's numbers, ``is_success`` and ``failure`` of every robot
        (:meth:`Task.evaluate`), each with its ``_key`` mask, here true for every robot."""
        ev = self._evaluation
        arrays = {**{k: v.copy() for k, v in ev.numbers.items()}, "is_success": ev.success.copy(),
                  "failure": self._failure_names[ev.failure]}
        every = np.ones(self.num_envs, bool)
        return {k: v for name, value in arrays.items() for k, v in ((name, value), (f"_{name}", every))}


class SameStepVectorEnv(VectorEnv):
    """A native vector env in gymnasium's ``SAME_STEP`` autoreset mode: a robot
    whose episode ends is reset within the same step (by
    :meth:`ParagymVectorEnv.reset_done`), so the step returns its first
    observation of the next episode. As gymnasium's ``SyncVectorEnv`` in that
    mode, the info then holds ``final_obs`` (an object array: the last
    observation of each robot that finished, None for the others) and
    ``final_info`` (the info of that last step), each with its ``_``-prefixed
    mask, and, for the robots reset, their reset info. All robots still step in
    one call of the native env.

    ``venv``: a :class:`ParagymVectorEnv`, or what ``gymnasium.make_vec(ID,
    num_envs=N, vectorization_mode="vector_entry_point")`` returns.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array"]}

    def __init__(self, venv: VectorEnv) -> None:
        native = getattr(venv, "unwrapped", venv)
        if not isinstance(native, ParagymVectorEnv):
            raise TypeError(f"venv must be a paragym native vector env; got {type(native).__name__}")
        self.venv = native
        self.num_envs = native.num_envs
        self.render_mode = native.render_mode
        self.single_observation_space = native.single_observation_space
        self.single_action_space = native.single_action_space
        self.observation_space = native.observation_space
        self.action_space = native.action_space

    @property
    def autoreset_mode(self) -> AutoresetMode:
        return AutoresetMode.SAME_STEP

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """As :meth:`ParagymVectorEnv.reset`."""
        return self.venv.reset(seed=seed, options=options)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.venv.step(actions)
        done = terminated | truncated
        if not done.any():
            return obs, reward, terminated, truncated, info
        rows, first = self.venv.reset_done()
        final = np.full(self.num_envs, None, dtype=object)
        final[rows] = list(obs[rows])
        obs[rows] = first
        return obs, reward, terminated, truncated, {**self.venv._infos(), "final_obs": final, "_final_obs": done,
                                                    "final_info": info, "_final_info": done}

    def render(self) -> np.ndarray | None:  # type: ignore[override]  # as ParagymVectorEnv.render
        return self.venv.render()

    def close(self, **kwargs: Any) -> None:
        self.venv.close(**kwargs)
