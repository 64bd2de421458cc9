"""The base class every paragym environment derives from.

As in Gymnasium-Robotics, the base owns ``reset``/``step``/``render``/``close``
and the checks every task shares (the action's shape and finiteness, the
render mode); a task fills the hooks below. All randomness comes from
``self.np_random``, so the same seed gives the same episode bit for bit.
"""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np

from paragym.sim.client import divides, physics_steps

__all__ = ["ParagymEnv", "check_action", "check_control_period", "check_options", "check_seed", "pose6"]

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


def check_control_period(control_period: float, time_step: float, refuse: bool, later: str | None = None) -> None:
    """Simulated time must run at the control period's rate: a ``control_period`` (s) that is not a whole number
    of physics steps of ``time_step`` (s) is refused with a ValueError naming it (``refuse``), or, in a released
    id that ran it rounded, warned about (naming the ``later`` id that refuses it)."""
    if divides(control_period, time_step):
        return
    said = (f"control_period {control_period!r} s is not a whole number of physics steps of {time_step!r} s: each "
            f"step would be simulated over {physics_steps(control_period, time_step) * time_step:g} s")
    if refuse:
        raise ValueError(f"{said}; choose a control_period that is a multiple of the dynamics' time_step")
    why = f"; {later} refuses it" if later else ""
    warnings.warn(f"{said} (this id's released behaviour{why})", UserWarning, stacklevel=3)


def pose6(position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """A pose as (6,): the position (m) and the roll, pitch, yaw (rad) of the rotation matrix."""
    from paragym.mechanisms.hybrid import matrix_euler

    return np.concatenate([position, matrix_euler(rotation[None])[0]])


def check_options(options: Any) -> dict[str, Any]:
    """``reset``'s options as a new dict (None: empty), or a TypeError naming them."""
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options must be a dict or None; got {type(options).__name__}")
    return dict(options or {})


_BOUNDS: dict[int, tuple[Any, list[float], list[float]]] = {}


def _bounds(space: gym.spaces.Box) -> tuple[list[float], list[float]]:
    """The Box's bounds as flat Python floats (kept per space: a step checks them)."""
    got = _BOUNDS.get(id(space))
    if got is None or got[0] is not space:
        got = (space, space.low.astype(float).ravel().tolist(), space.high.astype(float).ravel().tolist())
        _BOUNDS[id(space)] = got
    return got[1], got[2]


def check_action(action: Any, space: gym.spaces.Box, name: str = "action", rows: int | None = None) -> np.ndarray:
    """The action as float64, clipped to ``space`` (one rule for every env).

    An action outside the Box is clipped to it, as Gymnasium's own envs and
    Stable-Baselines3 expect; everything else that is not a finite real
    number of the right shape raises at once: strings, complex numbers and
    objects a ``TypeError``, NaN, inf, numbers beyond float64 and a wrong
    shape a ``ValueError``, each naming ``name``. ``rows``: a batch of that
    many actions (a native vector env), whose bad row is named.

    A single float array inside the Box, the common case, is checked in a
    few Python comparisons (a NaN or an inf fails them too), so that the
    rule costs about a microsecond a step.
    """
    want = space.shape if rows is None else (rows, *space.shape)
    if rows is None and type(action) is np.ndarray and action.dtype.kind == "f" and action.shape == want:
        low, high = _bounds(space)
        values = action.ravel().tolist()
        if all(lo <= v <= hi for v, lo, hi in zip(values, low, high, strict=True)):
            return action.astype(np.float64)
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


class ParagymEnv(gym.Env):
    """Shared ``reset``/``step``/``render``/``close``; tasks fill the hooks.

    Every paragym env is the N = 1 case of its task's transition
    (``paragym.tasks.*_step``): ``reset`` calls the task's ``_start`` and
    ``step`` its ``_transition``, which one mixin per task gives the single
    env and the vector env alike, and both read the observation, reward and
    termination from ``self.state``. A task fills ``_info() -> dict``,
    ``_render_rgb() -> array`` and ``_close()``; ``_ended()`` says whether a
    step now would run past the episode's end; in dynamic fidelity
    ``_body()``, ``commanded_pose()`` and ``step_duration()`` are what KF
    validation reads (:mod:`paragym.validation.episode`).
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 25}

    def __init__(self, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None; "
                             f"got {render_mode!r}")
        self.render_mode = render_mode

    # --- the loop -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        check_seed(seed)
        options = check_options(options)
        super().reset(seed=seed)
        scenarios = self._start(_FIRST, [self.np_random], options)
        info = self._info()
        info["scenario"] = scenarios[0]
        return self.state.obs[0].copy(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        action = check_action(action, self.action_space)
        if self._ended():
            raise RuntimeError("the episode has ended: call reset()")
        self._transition(action[None], _ONE)
        s = self.state
        return s.obs[0].copy(), float(s.reward[0]), bool(s.terminated[0]), False, self._info()

    def render(self) -> np.ndarray | None:
        if self.render_mode == "rgb_array":
            return self._render_rgb()
        if self.render_mode == "human":
            self._show()  # the PyBullet GUI window shows the scene
        return None

    def close(self) -> None:
        self._close()

    # --- the task's state and hooks ------------------------------------------------------------
    #: the task's state of one robot (N = 1) and the transition's parameters (paragym.tasks.*_step)
    state: Any = None
    params: Any = None

    def _ended(self) -> bool:
        """Whether a step now would run past the episode's end (then it raises)."""
        return bool(self.state.terminated[0])

    @property
    def scenario(self) -> Any:
        """The episode's scenario (``info["scenario"]`` of the last reset)."""
        return self.state.scenarios[0]

    def _info(self) -> dict[str, Any]:
        raise NotImplementedError

    # --- a task's hooks, shared by its single env and its vector env (a mixin defines them) -----
    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        """Draw and check the scenarios of robots ``rows`` (one generator
        each), start them, and return the scenarios."""
        raise NotImplementedError

    def _transition(self, actions: np.ndarray, active: np.ndarray) -> None:
        """Step the ``active`` robots of ``self.state`` with ``actions`` (N, ...)."""
        raise NotImplementedError

    def _render_rgb(self) -> np.ndarray:
        raise NotImplementedError

    def _show(self) -> None:
        """Update the GUI in ``render_mode="human"``: pose the scene by drawing
        it (an env whose scene PyBullet keeps up to date needs nothing)."""
        self._render_rgb()

    # --- what KF validation reads in dynamic fidelity (paragym.validation.episode) ---------------
    #: the accelerometer array on the validated body: the arguments of
    #: ``paragym.validation.sensors.AccelerometerArray.paper_layout``
    sensor_layout: dict[str, float] = {}

    def _body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """The validated body: (sim client, robot, link, the judged point in the link's frame (m), the
        dynamics' physics step (s))."""
        raise NotImplementedError

    def _dynamic_body(self) -> tuple[Any, str, int, np.ndarray, float]:
        if getattr(self, "fidelity", None) != "dynamic":
            raise ValueError("the executed body is simulated in the dynamic fidelity only: make the env with "
                             "fidelity='dynamic'")
        return self._body()

    @property
    def body_point(self) -> np.ndarray:
        """The judged point of the validated body, in its link's frame (m, (3,))."""
        return self._dynamic_body()[3]

    @property
    def physics_time_step(self) -> float:
        """Seconds of one physics step of the dynamic fidelity (its dynamics' ``time_step``)."""
        return float(self._dynamic_body()[4])

    def body_motion(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The validated body's link now, as simulated: position (m), quaternion (x, y, z, w), velocity
        (m/s) and angular velocity (rad/s), world frame."""
        sim, robot, link, _, _ = self._dynamic_body()
        return sim.link_motion(robot, link, velocity=True)

    def on_physics_step(self, callback: Any) -> Any:
        """Call ``callback()`` after every physics step from now on; returns the function that stops it."""
        hooks = self._dynamic_body()[0].after_step
        hooks.append(callback)
        return lambda: callback in hooks and hooks.remove(callback)

    def commanded_pose(self) -> np.ndarray:
        """The pose of the validated body that the last action commanded: x, y, z (m), roll, pitch, yaw (rad)."""
        raise NotImplementedError

    def step_duration(self) -> float:
        """Simulated seconds of the step just taken (whole physics steps)."""
        raise NotImplementedError

    # --- a PyBullet scene built on the first render, for envs whose step needs none ----
    _render_scene: Any = None

    def _drawn(self, build: Any, pose: Any) -> np.ndarray:
        """Build the render scene on first use (``build(gui)``), pose it
        (``pose(scene)``) and draw it."""
        if self._render_scene is None:
            self._render_scene = build(self.render_mode == "human")
        pose(self._render_scene)
        return self._render_scene.render()

    def _close_render_scene(self) -> None:
        if self._render_scene is not None:
            self._render_scene.close()
            self._render_scene = None

    def _close(self) -> None:
        self._close_render_scene()
