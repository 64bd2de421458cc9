"""The single env of every paragym task: a generic shell over the task's contract.

:class:`ParagymEnv` owns ``reset``/``step``/``render``/``close``, the checks
every task shares (the action's shape and finiteness, the render mode, the
seed and the options) and one lifecycle; everything else is the task's
(:class:`paragym.tasks.base.Task`). An env id's class names its task and its
rules and carries the docstring its docs page is made from. All randomness
comes from ``self.np_random``, so the same seed gives the same episode bit
for bit.
"""

from __future__ import annotations

import inspect
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from paragym.mechanisms.geometry import pose6
from paragym.tasks.base import SimulatedWorld, Task, check_control_period

__all__ = ["ActionCheck", "ParagymEnv", "TaskShell", "box", "check_action", "check_control_period", "check_copyable",
           "check_options", "check_seed", "check_train_scenarios", "env_signature", "pose6"]

_FIRST = np.zeros(1, np.int64)  # the single env's one robot, as the rows of a batch
_ONE = np.ones(1, bool)


def check_seed(seed: Any, name: str = "seed") -> int | None:
    """``seed`` if it is None or a non-negative integer (numpy's seeds), else a
    TypeError or ValueError naming it."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"{name} must be a non-negative integer or None; got {seed!r}")
    if seed < 0:
        raise ValueError(f"{name} must be a non-negative integer or None; got {seed!r}")
    return int(seed)


def box(spec: Any) -> gym.spaces.Box:
    """The Gymnasium Box of a task's :class:`paragym.tasks.base.BoxSpec` (float32)."""
    return gym.spaces.Box(spec.low, spec.high, spec.shape, np.float32)


def check_options(options: Any, known: tuple[str, ...] = ("scenario",)) -> dict[str, Any]:
    """``reset``'s options as a new dict (None: empty), or a TypeError naming them; a key not in ``known`` is a
    ValueError naming it (an option a task does not read must not pass silently)."""
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options must be a dict or None; got {type(options).__name__}")
    options = dict(options or {})
    for key in options:
        if key not in known:
            raise ValueError(f"options has an unknown key {key!r}; reset takes {', '.join(map(repr, known))}")
    return options


def check_copyable(env: Any) -> None:
    """A TypeError if ``env``'s world holds a simulation (``live``: a PyBullet client, or MuJoCo's robots and the
    threads that step them): a copy would share it (two envs stepping one simulation, and the original
    disconnected when the copy is collected)."""
    world = env.__dict__.get("world")
    if world is not None and getattr(world, "live", True):
        raise TypeError(f"{type(env).__name__} with fidelity={env.params.fidelity!r} cannot be copied or pickled: "
                        "its simulation cannot be; make a new env with the same arguments and reset it with "
                        "the same seed")


def check_action(action: Any, space: gym.spaces.Box, name: str = "action", rows: int | None = None) -> np.ndarray:
    """The action as float64, clipped to ``space`` (one rule for every env).

    An action outside the Box is clipped to it, as Gymnasium's own envs and
    Stable-Baselines3 expect; everything else that is not a finite real
    number of the right shape raises at once: strings, complex numbers and
    objects a ``TypeError``, NaN, inf, numbers beyond float64 and a wrong
    shape a ``ValueError``, each naming ``name``. ``rows``: a batch of that
    many actions (a native vector env), whose bad row is named.

    The single env checks its actions through :class:`ActionCheck`, which
    passes a float array inside the Box in a few Python comparisons.
    """
    want = space.shape if rows is None else (rows, *space.shape)
    if action is None:
        raise TypeError(f"{name} must be an array of real numbers; got None")
    try:
        arr = np.asarray(action)
    except (TypeError, ValueError, OverflowError) as exc:
        raise TypeError(f"{name} must be an array of real numbers; got {action!r:.80}") from exc
    if arr.dtype.kind == "O":  # Python ints beyond float64 or other objects
        try:
            arr = arr.astype(np.float64)
        except OverflowError:
            raise ValueError(f"{name} must be finite; got a number beyond float64's range") from None
        except (TypeError, ValueError) as exc:
            raise TypeError(f"{name} must be an array of real numbers; got {action!r:.80}") from exc
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be an array of real numbers; got dtype {arr.dtype} ({action!r:.80})")
    arr = arr.astype(np.float64, copy=False)
    if arr.shape != want:
        what = " (one row per robot)" if rows is not None else ""
        raise ValueError(f"{name} must have shape {want}{what}; got {arr.shape}")
    if rows is None:
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite; got {arr}")
    else:
        bad = ~np.isfinite(arr.reshape(rows, -1)).all(axis=1)
        if bad.any():
            idx = np.flatnonzero(bad)
            raise ValueError(f"{name} must be finite; row {idx[0]} is {arr[idx[0]]}"
                             + (f" ({len(idx)} rows are not: {idx[:10].tolist()}...)" if len(idx) > 1 else ""))
    return np.clip(arr, space.low, space.high)


class ActionCheck:
    """:func:`check_action` for one robot's actions of ``space``, returned as one batch row (1, ...): the same
    rule, with the Box's bounds read once. A float array of the Box's shape inside one bound shared by every
    component (every paragym Box) passes in a few Python comparisons (a NaN or an inf fails them too);
    anything else goes through :func:`check_action`."""

    def __init__(self, space: gym.spaces.Box) -> None:
        self.space, self.shape = space, space.shape
        low: set[float] = set(space.low.astype(float).ravel().tolist())
        high: set[float] = set(space.high.astype(float).ravel().tolist())
        #: the Box's one bound on every component, where it has one (then a quick check does), else None
        self.low: float | None = low.pop() if len(low) == len(high) == 1 else None
        self.high: float | None = high.pop() if self.low is not None else None

    def __call__(self, action: Any) -> np.ndarray:
        if self.low is not None and type(action) is np.ndarray and action.shape == self.shape \
                and action.dtype.kind == "f":
            values = action.ravel().tolist()
            total = sum(values)
            if self.low <= min(values) and max(values) <= self.high and total == total:
                return action.astype(np.float64)[None]
        return check_action(action, self.space)[None]


def env_signature(task: Any, first: tuple[inspect.Parameter, ...] = ()) -> inspect.Signature:
    """The keyword arguments of a task's env, as ``help()`` and the docs show them: ``render_mode``,
    ``train_scenarios`` and those of its ``Params.from_kwargs`` (``first``: a vector env's own before them)."""
    own = [inspect.Parameter("render_mode", inspect.Parameter.KEYWORD_ONLY, default=None, annotation="str | None"),
           inspect.Parameter("train_scenarios", inspect.Parameter.KEYWORD_ONLY, default=None,
                             annotation="int | None")]
    params = [q.replace(kind=inspect.Parameter.KEYWORD_ONLY)
              for q in list(inspect.signature(task.Params.from_kwargs).parameters.values())[1:]
              if q.kind is not inspect.Parameter.VAR_KEYWORD]
    return inspect.Signature([*first, *own, *params])


#: the most scenarios ``train_scenarios`` may fix: level l is the scenario ``reset(seed=l)`` draws, and the
#: leaderboard's evaluation episodes reset from seed 100000 on, so that every level stays unseen there
MAX_TRAIN_SCENARIOS = 100_000


def check_train_scenarios(value: Any) -> int | None:
    """``train_scenarios`` if it is None or an integer in [1, :data:`MAX_TRAIN_SCENARIOS`], else a TypeError or
    ValueError naming it."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise TypeError(f"train_scenarios must be a positive integer or None; got {value!r:.80}")
    if not 1 <= value <= MAX_TRAIN_SCENARIOS:
        raise ValueError(f"train_scenarios must lie in [1, {MAX_TRAIN_SCENARIOS}] (level l is the scenario of "
                         f"seed l; the leaderboard evaluates from seed 100000); got {value!r}")
    return int(value)


class TaskShell:
    """What the single and the vector env share over a task: its arguments read as attributes, copies that
    refuse a PyBullet client, and closing once."""

    params: Any = None
    world: Any = None
    #: how many fixed scenarios every reset draws from (None: a new one each time; :meth:`draw`)
    train_scenarios: int | None = None
    _render: dict[str, Any]
    _closed: bool = True
    _levels: dict[Any, Any]

    def draw(self, choice: Any, rngs: list[np.random.Generator]) -> list[Any]:
        """One scenario per robot's generator for the ``scenario`` argument ``choice`` (the task's
        ``draw_scenarios``). With ``train_scenarios`` = K, a finite training set, as Procgen's ``num_levels``: each
        robot's generator picks a level l in [0, K), and its scenario is the one ``choice`` draws from a generator
        seeded with l (the scenario ``reset(seed=l)`` starts without K), the same in every process; the rest of the
        episode's randomness stays the generator's. Evaluate on unseen scenarios without it."""
        if self.train_scenarios is None:
            return self.task.draw_scenarios(choice, rngs, self.params, self.world)
        levels = self.__dict__.setdefault("_levels", {})
        out = []
        for rng in rngs:
            level = int(rng.integers(self.train_scenarios))
            key = (choice, level) if isinstance(choice, str) else None
            scenario = levels.get(key) if key else None
            if scenario is None:
                scenario = self.task.draw_scenarios(choice, [np.random.default_rng(level)], self.params, self.world)[0]
                if key:
                    levels[key] = scenario
            out.append(scenario)
        return out

    def __getattr__(self, name: str) -> Any:
        """The env's arguments, as its parameters hold them (``env.geometry``, ``env.fidelity``, ...)."""
        params = self.__dict__.get("params")
        if params is None or name.startswith("__") or not hasattr(params, name):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        return getattr(params, name)

    def __getstate__(self) -> dict[str, Any]:
        check_copyable(self)
        return {**self.__dict__, "_render": {}}

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError(f"{type(self).__name__} is closed: make a new env")

    def _close_all(self) -> None:
        """Close the render scenes and the world, once."""
        if self.__dict__.get("_closed", True):
            return
        self._closed = True
        for scene in self._render.values():
            scene.close()
        self._render.clear()
        if self.world is not None:
            self.world.close()


class ParagymEnv(TaskShell, gym.Env):
    """The single env of a task: the N = 1 case of its transition, over the task's contract.

    A subclass per env id sets :attr:`task` (a :class:`paragym.tasks.base.Task`) and :attr:`rules` (one value
    of the task's ``Rules``) and documents the id in its docstring; it adds no code. The keyword arguments
    are the task's (``Params.from_kwargs`` checks them, the one place they are), readable as attributes of the
    env (``env.unwrapped.geometry``).

    Lifecycle, the same for every task: ``step`` before the first ``reset``, after a step that returned
    ``terminated=True`` (a TimeLimit's truncation is the wrapper's) or after ``close`` raises a RuntimeError saying
    what to do; an unknown ``reset`` option is a ValueError naming it; an env whose world holds a PyBullet
    client refuses ``copy.deepcopy`` and pickling with a TypeError (any other copy is independent: a render
    scene is not copied but built again when drawn).
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 25}

    #: the task (``paragym.tasks.<task>_task.TASK``) and this id's rules (a value of ``task.Rules``): set by the
    #: env id's class
    task: ClassVar[Task[Any, Any, Any, Any]]
    rules: ClassVar[Any]
    #: the env's arguments as ``inspect.signature`` and the docs show them (:func:`env_signature`)
    __signature__: ClassVar[inspect.Signature]
    action_space: gym.spaces.Box
    observation_space: gym.spaces.Box

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "task" in cls.__dict__:
            cls.__signature__ = env_signature(cls.task)

    def __init__(self, render_mode: str | None = None, train_scenarios: int | None = None, **kwargs: Any) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None; "
                             f"got {render_mode!r}")
        self.render_mode = render_mode
        self.train_scenarios = check_train_scenarios(train_scenarios)
        self.params = self.task.Params.from_kwargs(self.rules, **kwargs)
        self.observation_space, self.action_space = (box(b) for b in self.task.spaces(self.params))
        self.state = self.task.State.empty(1, self.params)
        self._check_action = ActionCheck(self.action_space)
        self._render: dict[str, Any] = {}
        self._evaluation: Any = None
        self._ended = True  # until the first reset, after a terminating step and after close
        self._closed = False
        self.world = self.task.make_world(self.params, 1, render_mode)

    # --- the loop -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        self._check_open()
        check_seed(seed)
        options = check_options(options)
        super().reset(seed=seed)
        task, p = self.task, self.params
        scenarios = self.draw(options.get("scenario", p.scenario), [self.np_random])
        task.reset(self.state, p, _FIRST, scenarios, [self.np_random], self.world)
        self._evaluation = task.evaluate(self.state, p, self.world)
        self._ended = False
        info = self._info()
        info["scenario"] = scenarios[0]
        return self.state.obs[0].copy(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._ended:
            self._check_open()
        action = self._check_action(action)
        if self._ended:
            raise RuntimeError("call reset() before step()" if self._evaluation is None else
                               "the episode has ended (a step returned terminated=True): call reset()")
        task, s = self.task, self.state
        task.step(s, self.params, action, _ONE, self.world)
        self._evaluation = task.evaluate(s, self.params, self.world)
        self._ended = terminated = s.terminated.item(0)
        return s.obs[0].copy(), s.reward.item(0), terminated, False, self._info()

    def render(self) -> np.ndarray | None:
        self._check_open()
        if self.render_mode is None or self._evaluation is None:
            return None
        image = self.task.render(self._render, self.state, self.params, self.world, 0, self.render_mode == "human")
        return image if self.render_mode == "rgb_array" else None

    def close(self) -> None:
        self._close_all()
        self._ended = True  # a step checks whether the env is open only where the episode looks ended

    def _info(self) -> dict[str, Any]:
        """The info of the one robot: the task's numbers, success and failure (:meth:`Task.evaluate`) and its
        details (:meth:`Task.details`)."""
        ev = self._evaluation
        if ev is not self._read_for:  # the same Evaluation (the state's buffers) every step: its readers, once
            self._read_for = ev
            self._readers = tuple((name, value.item) for name, value in ev.numbers.items())
            self._outcome = ev.success.item, ev.failure.item, self.task.failures, self.task.details
        success, failure, names, details = self._outcome
        info = details(self.state, self.params, self.world, 0)  # a new dict: the numbers go into it
        for name, read in self._readers:
            info[name] = read(0)
        info["is_success"] = success(0)
        info["failure"] = names[failure(0)]
        sim = getattr(getattr(self.world, "scene", None), "sim", None)
        if sim is not None and sim.loops:  # dynamic fidelity of a closed-chain mechanism
            info["loop_residual_m"] = sim.loop_residual()
        return info

    _read_for: Any = None

    @property
    def scenario(self) -> Any:
        """The episode's scenario (``info["scenario"]`` of the last reset)."""
        return self.state.scenarios[0]

    @property
    def scene(self) -> Any:
        """The world's PyBullet scene (None where the world has none, or has not built it yet)."""
        return getattr(self.world, "scene", None)

    # --- what KF validation reads in dynamic fidelity (paragym.validation.episode) ---------------
    @property
    def sensor_layout(self) -> dict[str, float]:
        """The accelerometer array on the validated body: the arguments of
        ``paragym.validation.sensors.AccelerometerArray.paper_layout`` (the task's)."""
        return self.task.sensor_layout

    def _simulated(self) -> SimulatedWorld:
        """The world, which simulates the robot (the dynamic fidelity's): a ValueError in another. Validation
        asks at every physics step, so the answer is kept for the world it was given for (a check against a
        runtime protocol inspects the class's members each time)."""
        world = self.world
        if world is not self._simulated_world:
            if self.params.fidelity != "dynamic" or not isinstance(world, SimulatedWorld):
                raise ValueError("the executed body is simulated in the dynamic fidelity only: make the env with "
                                 "fidelity='dynamic'")
            self._simulated_world = world
        return world

    _simulated_world: Any = None

    def _dynamic_body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """The validated body: (sim client, robot, link, the judged point in the link's frame (m), the
        dynamics' physics step (s)), read from the dynamic world."""
        return self._simulated().body()

    @property
    def body_point(self) -> np.ndarray:
        """The judged point of the validated body, in its link's frame (m, (3,))."""
        return self._dynamic_body()[3]

    @property
    def physics_time_step(self) -> float:
        """Seconds of one physics step of the dynamic fidelity (its dynamics' ``time_step``)."""
        return float(self._dynamic_body()[4])

    def body_motion(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The validated body's link frame now, as simulated: its origin's position (m), its quaternion (x, y, z,
        w), the origin's velocity (m/s) and the angular velocity (rad/s), world frame, in either engine."""
        sim, robot, link, _, _ = self._dynamic_body()
        return sim.link_motion(robot, link, velocity=True)

    def on_physics_step(self, callback: Any) -> Any:
        """Call ``callback()`` after every physics step from now on; returns the function that stops it."""
        hooks = self._dynamic_body()[0].after_step
        hooks.append(callback)
        return lambda: callback in hooks and hooks.remove(callback)

    def commanded_pose(self) -> np.ndarray:
        """The pose of the validated body that the last action commanded: x, y, z (m), roll, pitch, yaw (rad)."""
        return self._simulated().commanded_pose(self.state, self.params)

    def step_duration(self) -> float:
        """Simulated seconds of the step just taken (whole physics steps)."""
        return self._simulated().step_duration(self.state, self.params)
