"""The CaPaMan's worlds (paper 000): where the parts are and how far they are from the obstacles.

* :class:`GridWorld` (N robots): the closed-form kinematics and paper 000's
  occupancy grid Psi at the cluster points of eq 2 (numpy, all robots at once);
* :class:`PostWorld` (N robots, the difficulty ladder): the parts as capsules
  against capsule posts, the exact distance in closed form
  (:mod:`paragym.sim.capaman_posts`);
* :class:`SceneWorld` (one robot): PyBullet's exact signed distance in the
  kinematic scene;
* :class:`DynamicWorld` (one robot): the closed chain under PyBullet's
  dynamics (or MuJoCo's over the PyBullet scene); the motors chase the command for a control period and the
  encoders say where the cranks got;
* :class:`MuJoCoWorld` (N robots): the closed chains under MuJoCo's dynamics, MuJoCo alone, the clearance the
  task's own kernel's (the grid's or the posts') at the encoders' angles: the native dynamic vector env's world
  and, for N = 1, the single env's.

The transition (:mod:`paragym.tasks.capaman_step`) asks them; each also holds
the kinematic scene that generates and checks scenarios.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal, Protocol, Self

import numpy as np

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import pose6
from paragym.sim import capaman_grid
from paragym.sim.capaman_clearance import DistanceGrids, grid_clearance
from paragym.sim.capaman_dynamic import CaPaManDynamicScene, drive_together, state_together
from paragym.sim.capaman_posts import parts_in_reach, post_clearance
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.client import physics_steps
from paragym.sim.mujoco_sim import rollout_pool
from paragym.sim.obstacles import Box
from paragym.tasks import base
from paragym.tasks.base import BROKEN_GAP, SimulatedWorld
from paragym.tasks.capaman import CaPaManScenario, posts_of

#: the state and parameters the worlds read are the transition's (paragym.tasks.capaman_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld", "GridWorld", "KinematicWorld", "MovingWorld", "MuJoCoWorld", "NativeWorld", "PostWorld",
           "SceneWorld", "World", "WorldBase"]


class WorldBase(base.World, Protocol):
    """What every CaPaMan world answers (:class:`paragym.tasks.base.World`): where the parts are and how far they
    are from the obstacles."""

    #: whether it moves the robots itself (the dynamics: :class:`MovingWorld`) or the transition does
    moves: bool

    def set_obstacles(self, i: int, scenario: CaPaManScenario) -> None:
        """Robot ``i``'s obstacles are ``scenario``'s from now on."""
        ...

    def checker(self) -> CaPaManScene:
        """The kinematic PyBullet scene that generates and checks scenarios (built on first use)."""
        ...

    def probe(self) -> KinematicWorld | MovingWorld:
        """v1's look-ahead world: itself, or for the dynamics the kinematic one at the encoders' angles."""
        ...

    def draw(self, i: int, scenario: CaPaManScenario, alpha: np.ndarray, gui: bool) -> np.ndarray | None:
        """Robot ``i`` (its ``scenario``'s obstacles, at crank angles ``alpha`` (3,)) as an RGB array; None in
        the GUI, where PyBullet shows the scene as it runs."""
        ...

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        """Clearance (M,), tool tip (M, 3) and nearest part of robots ``rows`` at crank angles ``alpha`` (M, 3)."""
        ...

    def ahead(self, rows: np.ndarray, probes: np.ndarray, alpha: np.ndarray, pose_back: bool) -> np.ndarray:
        """v1's look-ahead: the clearance (M, 3) of robots ``rows`` at ``probes`` (M, 3, 3), crank k moved in
        ``probes[:, k]``; a drawn scene posed back at ``alpha`` (M, 3) after, when ``pose_back``."""
        ...


class KinematicWorld(WorldBase, Protocol):
    """A world that only measures: the transition moves the robots, checking the way (the kinematic fidelity)."""

    moves: Literal[False]


class MovingWorld(WorldBase, Protocol):
    """A world that moves the robots itself under a physics engine (the dynamic fidelity) and writes what it
    measured."""

    moves: Literal[True]
    #: whether the last move left a loop open by more than BROKEN_GAP (a broken mechanism), per robot
    broken: np.ndarray

    def move(self, rows: np.ndarray, command: np.ndarray) -> np.ndarray:
        """Where the cranks of robots ``rows`` got (M, 3) chasing ``command`` (M, 3) for a control period."""
        ...


#: a CaPaMan world: the transition tells the two kinds apart by :attr:`WorldBase.moves`
World = KinematicWorld | MovingWorld


@lru_cache(maxsize=4)
def _clusters(geometry: capaman.CaPaManGeometry) -> capaman_grid.ClusterPoints:
    return capaman_grid.cluster_points(geometry, spacing=0.01)


class NativeWorld:
    """A world of N robots that answers many configurations in one call (:meth:`clearance`), with no
    simulation of its own: its kinematic PyBullet scene, which generates and checks scenarios and draws, is
    built when first asked for."""

    #: it holds no simulation: a copy builds its own checker scene when it needs one
    live = False

    def __init__(self, geometry: capaman.CaPaManGeometry, cap: float, draws: bool = False, gui: bool = False
                 ) -> None:
        self.geometry, self.cap, self.draws, self.gui = geometry, cap, draws, gui
        #: the kinematic PyBullet scene that generates and checks scenarios and draws, built on first use
        self.scene: CaPaManScene | None = None

    def checker(self) -> CaPaManScene:
        """The kinematic scene that generates and checks scenarios (built on first use) and draws."""
        if self.scene is None:
            self.scene = CaPaManScene(self.geometry, gui=self.gui, clearance_cap=self.cap, draws=self.draws)
        return self.scene

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "scene": None}

    def close(self) -> None:
        if self.scene is not None:
            self.scene.close()
            self.scene = None

    def probe(self) -> Self:
        """v1's look-ahead world: itself (it answers the probes in one call, :meth:`ahead`)."""
        return self

    def draw(self, i: int, scenario: CaPaManScenario, alpha: np.ndarray, gui: bool) -> np.ndarray | None:
        """The checker scene posed as robot ``i`` (a native world does not pose it as it goes), drawn."""
        scene = self.checker()
        scene.set_obstacles(scenario.obstacles)
        scene.set_configuration(alpha)
        return scene.render()

    def clearance(self, rows: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        """The clearance (m) alone of robots ``rows`` at ``alpha`` (M, 3), as :meth:`place` gives it."""
        raise NotImplementedError

    def ahead(self, rows: np.ndarray, probes: np.ndarray, alpha: np.ndarray, pose_back: bool) -> np.ndarray:
        """Every probe in one call (:meth:`clearance`); nothing is posed."""
        return self.clearance(np.repeat(rows, 3), probes.reshape(-1, 3)).reshape(-1, 3)


class GridWorld(NativeWorld):
    """Paper 000's own test for N robots: the occupancy grid Psi of each
    robot's obstacles as signed distances, read at the cluster points of eq 2
    (10 mm apart) placed by the closed-form kinematics."""

    moves: Literal[False] = False

    def __init__(self, n: int, geometry: capaman.CaPaManGeometry, cap: float, draws: bool = False,
                 gui: bool = False) -> None:
        super().__init__(geometry, cap, draws, gui)
        self.grids, self.clusters = DistanceGrids(n, cap=cap), _clusters(geometry)
        self.part_names = [p.name for p in capaman.part_shapes(geometry)]

    def set_obstacles(self, i: int, scenario: CaPaManScenario) -> None:
        self.grids.set(int(i), scenario.obstacles)

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        pose = capaman.forward(alpha, self.geometry, validate=False)
        clearance, part = grid_clearance(alpha, self.grids, self.clusters, self.geometry, rows, pose=pose)
        return clearance, pose.tip, [self.part_names[p] if p >= 0 else None for p in part.tolist()]

    def clearance(self, rows: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        return grid_clearance(alpha, self.grids, self.clusters, self.geometry, rows)[0]


class PostWorld(NativeWorld):
    """The difficulty ladder's test for N robots: every part but the plate as the capsule that holds it, the
    obstacles as capsule posts, the distance between them exact and in closed form
    (:func:`paragym.sim.capaman_posts.post_clearance`); up to ``max_obstacles`` posts per robot."""

    moves: Literal[False] = False

    def __init__(self, n: int, geometry: capaman.CaPaManGeometry, cap: float, max_obstacles: int,
                 draws: bool = False, gui: bool = False) -> None:
        super().__init__(geometry, cap, draws, gui)
        self.posts, self.counts = np.zeros((n, max_obstacles, 5)), np.zeros(n, np.int64)
        self.reach = parts_in_reach(self.posts, self.counts, geometry, cap)
        self._stale: list[int] = []  # robots whose posts changed since reach was computed
        self.part_names = [p.name for p in capaman.part_shapes(geometry) if p.name != "plate"]

    def set_obstacles(self, i: int, scenario: CaPaManScenario) -> None:
        posts = posts_of(scenario.obstacles)
        self.posts[i, :len(posts)], self.counts[i] = posts, len(posts)
        self._stale.append(int(i))

    def _fresh(self) -> None:
        """The parts in reach of the robots whose posts changed since the last answer, in one call."""
        if self._stale:
            rows = np.array(self._stale)
            self.reach[rows] = parts_in_reach(self.posts[rows], self.counts[rows], self.geometry, self.cap)
            self._stale = []

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        self._fresh()
        clearance, part, tip = post_clearance(alpha, self.posts, self.counts, rows, self.geometry, self.cap,
                                              self.reach)
        return clearance, tip, [self.part_names[p] if p >= 0 else None for p in part.tolist()]

    def clearance(self, rows: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        self._fresh()
        return post_clearance(alpha, self.posts, self.counts, rows, self.geometry, self.cap, self.reach)[0]


class _OneScene:
    """One robot in a PyBullet scene (:class:`SceneWorld`, :class:`DynamicWorld`): its exact signed distance."""

    live = True

    def __init__(self, scene: CaPaManScene | CaPaManDynamicScene) -> None:
        self.scene = scene

    def close(self) -> None:
        self.scene.close()

    def draw(self, i: int, scenario: CaPaManScenario, alpha: np.ndarray, gui: bool) -> np.ndarray | None:
        """The scene, which the transition keeps posed (PyBullet's GUI shows it)."""
        return None if gui else self.scene.render()

    def set_obstacles(self, i: int, scenario: CaPaManScenario) -> None:
        self.scene.set_obstacles(scenario.obstacles)

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        tip = self.scene.set_configuration(alpha[0])
        clearance, near = self.scene.clearance()
        return np.array([clearance]), tip[None], [near]

    def ahead(self, rows: np.ndarray, probes: np.ndarray, alpha: np.ndarray, pose_back: bool) -> np.ndarray:
        """One probe after the other, then the scene posed back where the robot is (it is drawn)."""
        out = np.stack([self.place(rows, probes[:, k])[0] for k in range(3)], axis=1)
        if pose_back:
            self.place(rows, alpha)
        return out


class SceneWorld(_OneScene):
    """One robot in the kinematic PyBullet scene: its exact signed distance."""

    moves: Literal[False] = False
    scene: CaPaManScene

    def __init__(self, scene: CaPaManScene) -> None:
        super().__init__(scene)

    def checker(self) -> CaPaManScene:
        """The kinematic scene that generates and checks scenarios: its own."""
        return self.scene

    def probe(self) -> SceneWorld:
        """v1's look-ahead world: itself."""
        return self


class DynamicWorld(_OneScene):
    """One robot under PyBullet's dynamics: the motors chase the command for
    ``control_period`` s; the obstacles are rigid bodies."""

    #: it moves the robots itself (the transition asks :meth:`move` where they got)
    moves: Literal[True] = True
    scene: CaPaManDynamicScene

    def __init__(self, scene: CaPaManDynamicScene, control_period: float) -> None:
        super().__init__(scene)
        self.control_period = control_period
        self._moved = False
        #: whether the last move left a loop open by more than BROKEN_GAP (a broken mechanism), per robot
        self.broken = np.zeros(1, bool)
        self._checker: CaPaManScene | None = None
        self._probe: SceneWorld | None = None

    def ahead(self, rows: np.ndarray, probes: np.ndarray, alpha: np.ndarray, pose_back: bool) -> np.ndarray:
        """The probes in the simulated scene, never posed back: the simulation holds where the robot is."""
        return super().ahead(rows, probes, alpha, False)

    def checker(self) -> CaPaManScene:
        """A second, kinematic scene that generates and checks scenarios (built on first use)."""
        if self._checker is None:
            self._checker = CaPaManScene(self.scene.geometry, clearance_cap=self.scene.clearance_cap, draws=False)
        return self._checker

    def probe(self) -> SceneWorld:
        """v1's look-ahead world: the kinematic checker scene, at the encoders' angles."""
        if self._probe is None:
            self._probe = SceneWorld(self.checker())
        return self._probe

    def close(self) -> None:
        self.scene.close()
        if self._checker is not None:
            self._checker.close()

    # --- what KF validation reads (paragym.validation.episode) ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """Paper 000's accelerometer array on the movable plate, judged about H."""
        return (self.scene.sim, *self.scene.plate, np.zeros(3), self.scene.sim.time_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """The plate's pose by the closed-form direct kinematics of the motors' targets."""
        return _commanded_pose(state, params)

    def step_duration(self, state: Any, params: Any) -> float:
        h = self.scene.sim.time_step  # the engine's physics step
        return h * physics_steps(self.control_period, h)

    def move(self, rows: np.ndarray, command: np.ndarray) -> np.ndarray:
        """Where the cranks got (1, 3) chasing ``command`` (1, 3) (``rows``: the one robot, 0)."""
        self.scene.drive(command[0], self.control_period)
        self._moved = True
        self.broken[0] = self.scene.closure_error() > BROKEN_GAP
        return self.scene.alpha[None]

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        if not self._moved:  # a reset: pose the chain; after a move the dynamics has posed it
            self.broken[0] = False
            return super().place(rows, alpha)
        self._moved = False
        clearance, near = self.scene.clearance()
        return np.array([clearance]), self.scene.tip[None], [near]




class MuJoCoWorld(NativeWorld):
    """N robots under MuJoCo's dynamics, with no other engine: each robot a CaPaMan described as data
    (:class:`~paragym.sim.capaman_dynamic.CaPaManDynamicScene` with ``engine.mirror`` False) in a MuJoCo model
    of its own, whose fixed parts are its scenario's obstacles (padded to the world's number of slots, so that every
    model has one size), its motors chasing the command for ``control_period`` s. The robots step together in
    MuJoCo's ``rollout`` on a thread per core this process may use, no lock held; each
    control period starts the solver cold, so that a robot's motion is its own whatever else steps
    (:func:`paragym.sim.mujoco_sim.ramp_together`). The encoders say where the cranks got; the tool tip is MuJoCo's
    plate's; the clearance is the ``kinematic`` world's (:class:`GridWorld` or :class:`PostWorld`, the same
    kernel as the kinematic fidelity's, both for the step and v1's look-ahead) at the encoders' angles; a loop
    open by more than BROKEN_GAP is a broken mechanism. Its obstacles are rigid in MuJoCo as well: contact
    stops the parts; the kernel's capsules hold the parts, so it calls a collision before MuJoCo's parts touch.
    """

    moves: Literal[True] = True
    #: it holds a simulation (each robot's MuJoCo state and the threads that step them): not copied
    live = True

    def __init__(self, kinematic: GridWorld | PostWorld, dynamics: Any, engine: Any, control_period: float,
                 n: int, slots: int, gui: bool = False) -> None:
        super().__init__(kinematic.geometry, kinematic.cap, kinematic.draws, kinematic.gui)
        self.kinematic = kinematic
        self.control_period = control_period
        #: the robots, each a CaPaMan described as data and simulated in MuJoCo
        self.robots = [CaPaManDynamicScene(kinematic.geometry, dynamics, gui=gui and i == 0,
                                           clearance_cap=kinematic.cap, engine=engine)
                       for i in range(n)]
        self.slots = slots
        #: whether the last move left a loop open by more than BROKEN_GAP, per robot
        self.broken = np.zeros(n, bool)
        self._moved = np.zeros(n, bool)
        self._tips = np.zeros((n, 3))  # where the last move left each tool tip
        self._pool = rollout_pool(n)

    def checker(self) -> CaPaManScene:
        return self.kinematic.checker()

    def draw(self, i: int, scenario: CaPaManScenario, alpha: np.ndarray, gui: bool) -> np.ndarray | None:
        """The robot as MuJoCo has it, drawn in PyBullet."""
        return None if gui else self.robots[i].render()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool = None
        for robot in self.robots:
            robot.close()
        self.kinematic.close()

    def set_obstacles(self, i: int, scenario: CaPaManScenario) -> None:
        self.kinematic.set_obstacles(i, scenario)
        self.robots[i].set_obstacles(tuple(scenario.obstacles) + (_NOWHERE,) * (self.slots - len(scenario.obstacles)))

    def move(self, rows: np.ndarray, command: np.ndarray) -> np.ndarray:
        """Where the cranks of robots ``rows`` got (M, 3) chasing ``command`` (M, 3) for a control period."""
        if not rows.size:
            return np.empty((0, 3))
        robots = [self.robots[i] for i in rows.tolist()]
        drive_together(robots, command, self.control_period, self._pool)
        alpha, self._tips[rows], gap = state_together(robots)
        self._moved[rows] = True
        self.broken[rows] = gap > BROKEN_GAP
        return alpha

    def place(self, rows: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str | None]]:
        """Clearance (the kinematic world's at ``alpha``), tool tip (MuJoCo's) and nearest part of ``rows``; a
        robot that has not moved since its reset is posed at rest at ``alpha`` first."""
        tip = np.empty((len(rows), 3))
        for k, i in enumerate(rows.tolist()):
            if self._moved[i]:
                self._moved[i] = False
                tip[k] = self._tips[i]
            else:
                self.broken[i] = False
                tip[k] = self.robots[i].set_configuration(alpha[k])
        clearance, _, near = self.kinematic.place(rows, alpha)
        return clearance, tip, near

    def clearance(self, rows: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        return self.kinematic.clearance(rows, alpha)

    # --- what KF validation reads (paragym.validation.episode), of robot 0 ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """Paper 000's accelerometer array on the movable plate, judged about H."""
        robot = self.robots[0]
        return (robot.sim, *robot.plate, np.zeros(3), robot.sim.time_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """The plate's pose by the closed-form direct kinematics of robot 0's motors' targets."""
        return _commanded_pose(state, params)

    def step_duration(self, state: Any, params: Any) -> float:
        h = self.robots[0].sim.time_step
        return h * physics_steps(self.control_period, h)


def _commanded_pose(state: Any, params: Any) -> np.ndarray:
    """Robot 0's plate pose by the closed-form direct kinematics of its motors' targets (KF validation's)."""
    pose = capaman.forward(state.command[:1], params.geometry, validate=False)
    return pose6(pose.position[0], pose.rotation[0])


#: a fixed part that fills an unused obstacle slot of a robot's model: far below, out of every part's reach
_NOWHERE = Box((0.0, 0.0, -10.0), (0.01, 0.01, 0.01))


if TYPE_CHECKING:  # the type checker holds the worlds that simulate to what episode validation reads
    _dynamicworld: type[SimulatedWorld] = DynamicWorld
    _mujocoworld: type[SimulatedWorld] = MuJoCoWorld
