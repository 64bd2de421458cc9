"""The mobile tripod's drives (paper 004, section 4): the paper's named disturbances and random mixtures.

A :class:`TripodScenario` is the straight drive the tripod makes and what
disturbs it. Used by the env, the vector env, the planner and the CLI alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from paragym.sim.tripod_drive import Terrain
from paragym.tasks import base

__all__ = ["LADDER", "SCENARIOS", "TripodRung", "TripodScenario", "draw_scenarios", "drive_scenario", "knob_table",
           "ladder_scenario", "paper_scenario", "random_scenario", "resolve_scenario", "validate_scenario"]

#: the most samples a drive may have (139 h at 20 Hz): the drive's random numbers are drawn when it starts
MAX_SAMPLES = 10_000_000
#: the paper's named drives (section 4) and seeded random mixtures
SCENARIOS = ("initial_heading", "push", "random_slip", "rough_terrain", "random")


@dataclass(frozen=True)
class TripodScenario:
    """A drive: speed (m/s), heading (rad), distance (m), and disturbances.

    ``heading_error`` (3,) rad: each unit's true heading minus the one it
    believes; ``push`` (unit, time s, inward distance m) or None, and
    ``more_pushes``, more of them (:attr:`pushes`: all of them);
    ``slip`` m/s: the largest random slip velocity of each unit per sample
    (uniform in [0, slip] in a random direction); ``terrain``.
    """

    name: str
    speed: float = 0.66
    heading: float = 0.0
    distance: float = 20.0
    heading_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    push: tuple[int, float, float] | None = None
    slip: float = 0.0
    terrain: Terrain = field(default_factory=Terrain)
    seed: int | None = None
    more_pushes: tuple[tuple[int, float, float], ...] = ()

    @property
    def duration(self) -> float:
        return self.distance / self.speed

    @property
    def pushes(self) -> tuple[tuple[int, float, float], ...]:
        """Every push of the drive: ``push``, then ``more_pushes``."""
        return ((self.push,) if self.push is not None else ()) + tuple(self.more_pushes)


def validate_scenario(scenario: TripodScenario, name: str = "scenario", dt: float = 0.05) -> TripodScenario:
    """Refuse (ValueError/TypeError naming the field) a drive that could not be
    simulated: non-finite or non-positive speed or distance, a drive shorter
    than one sample or longer than :data:`MAX_SAMPLES`, heading errors that are not three finite angles within
    +-90 deg, a push on a unit other than 0, 1, 2 or at a time outside the
    drive, a negative or non-finite slip, terrain bumps that are not
    (x, y, height, radius) with a radius of at least 1 mm (a thinner one
    underflows the Gaussian) and a height within +-0.5 m."""
    if not isinstance(scenario, TripodScenario):
        raise TypeError(f"{name} must be a TripodScenario; got {type(scenario).__name__}")

    def real(value: Any, what: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            raise TypeError(f"{name}.{what} must be a real number; got {value!r}")
        if not np.isfinite(value):
            raise ValueError(f"{name}.{what} must be finite; got {value!r}")
        return float(value)

    if real(scenario.speed, "speed") <= 0:
        raise ValueError(f"{name}.speed must be > 0 m/s; got {scenario.speed!r}")
    if real(scenario.distance, "distance") <= 0:
        raise ValueError(f"{name}.distance must be > 0 m; got {scenario.distance!r}")
    if scenario.distance / scenario.speed < dt:
        raise ValueError(f"{name} lasts {scenario.distance / scenario.speed:.3g} s, less than one sample ({dt} s)")
    if scenario.distance / scenario.speed / dt > MAX_SAMPLES:
        raise ValueError(f"{name} lasts {scenario.distance / scenario.speed:.3g} s, more than {MAX_SAMPLES:,} samples "
                         f"at {1 / dt:g} Hz: a drive that long cannot be simulated")
    real(scenario.heading, "heading")
    errors = np.asarray(scenario.heading_error, dtype=object)
    if errors.shape != (3,):
        raise ValueError(f"{name}.heading_error must be three angles (rad); got {scenario.heading_error!r}")
    for k, value in enumerate(errors):
        if abs(real(value, f"heading_error[{k}]")) > np.pi / 2:
            raise ValueError(f"{name}.heading_error[{k}] must lie within +-pi/2 rad; got {value!r}")
    if not isinstance(scenario.more_pushes, tuple | list):
        raise ValueError(f"{name}.more_pushes must be a tuple of pushes; got {scenario.more_pushes!r}")
    pushes = ([("push", scenario.push)] if scenario.push is not None else []) + \
        [(f"more_pushes[{k}]", p) for k, p in enumerate(scenario.more_pushes)]
    for what, push in pushes:
        if not isinstance(push, tuple | list) or len(push) != 3:
            raise ValueError(f"{name}.{what} must be (unit, time s, inward distance m); got {push!r}")
        unit, when, how_far = push
        if isinstance(unit, bool) or not isinstance(unit, int | np.integer) or unit not in (0, 1, 2):
            raise ValueError(f"{name}.{what} unit must be 0, 1 or 2; got {unit!r}")
        if not 0 <= real(when, f"{what} time") <= scenario.duration:
            raise ValueError(f"{name}.{what} time must lie within the drive, 0-{scenario.duration:.3g} s; "
                             f"got {when!r}")
        if abs(real(how_far, f"{what} distance")) > 1.0:
            raise ValueError(f"{name}.{what} distance must be within +-1 m; got {how_far!r}")
    if real(scenario.slip, "slip") < 0:
        raise ValueError(f"{name}.slip must be >= 0 m/s; got {scenario.slip!r}")
    if not isinstance(scenario.terrain, Terrain):
        raise TypeError(f"{name}.terrain must be a Terrain; got {type(scenario.terrain).__name__}")
    for k, bump in enumerate(scenario.terrain.bumps):
        if len(bump) != 4:
            raise ValueError(f"{name}.terrain.bumps[{k}] must be (x, y, height, radius); got {bump!r}")
        for j, what in enumerate(("x", "y", "height", "radius")):
            real(bump[j], f"terrain.bumps[{k}].{what}")
        if not bump[3] >= 1e-3:
            raise ValueError(f"{name}.terrain.bumps[{k}] radius must be at least 1 mm; got {bump[3]!r}")
        if not abs(bump[2]) <= 0.5:
            raise ValueError(f"{name}.terrain.bumps[{k}] height must lie within +-0.5 m; got {bump[2]!r}")
    return scenario



def drive_scenario(name: str, rng: np.random.Generator) -> TripodScenario:
    """The paper's named drives (section 4) and seeded random mixtures."""
    base.resolve_scenario(name, SCENARIOS, TripodScenario)  # an unknown name: the one message
    if name == "initial_heading":  # a 2 deg initial heading error on one unit; 20 m at 0.66 m/s
        return TripodScenario(name, heading_error=(math.radians(2.0), 0.0, 0.0))
    if name == "push":  # unit 1 pushed 2.5 cm toward the centre at t = 15 s
        return TripodScenario(name, push=(0, 15.0, 0.025))
    if name == "random_slip":  # random odometric errors up to 1 cm/s on all three units at once
        return TripodScenario(name, slip=0.01)
    if name == "rough_terrain":  # bumps and holes on the way
        bumps = tuple((float(x), float(y), float(h), 0.4) for x, y, h in
                      zip(np.linspace(2, 18, 8), rng.uniform(-1.5, 1.5, 8), rng.choice([-1, 1], 8) * 0.08,
                          strict=True))
        return TripodScenario(name, terrain=Terrain(bumps))
    # "random": a seeded mixture of every disturbance
    errors = np.zeros(3)
    errors[rng.integers(3)] = math.radians(rng.uniform(-2, 2))
    push = (int(rng.integers(3)), float(rng.uniform(5, 25)), float(rng.uniform(0.01, 0.03))) \
        if rng.random() < 0.5 else None
    bumps = tuple((float(rng.uniform(2, 18)), float(rng.uniform(-2, 2)), float(rng.choice([-1, 1]) * 0.06), 0.4)
                  for _ in range(int(rng.integers(0, 5))))
    return TripodScenario(name, heading=float(rng.uniform(-math.pi, math.pi)),
                          heading_error=(errors[0], errors[1], errors[2]), push=push,
                          slip=float(rng.uniform(0, 0.01)), terrain=Terrain(bumps))


@dataclass(frozen=True)
class TripodRung:
    """The knobs of one rung of the tripod's difficulty ladder (:func:`ladder_scenario`).

    Attributes:
        bumps: how many bumps and holes lie across the drive's path.
        height: the largest bump's height (m); each is drawn in [height / 2, height], up or down.
        push: each push's inward distance (m), drawn uniformly in [low, high].
        pushes: how many pushes, each on another unit than the last, in turn through the drive.
        slip: the largest random slip velocity (m/s), as :attr:`TripodScenario.slip`.
    """

    bumps: int
    height: float
    push: tuple[float, float]
    pushes: int
    slip: float


#: the tripod's difficulty ladder, easiest first: every drive has two or more pushes on units drawn at random,
#: large enough that odometry alone ends outside the 5 cm success error and that no constant trust corrects them
#: all; each rung adds a push, bumps and slip that hide the pushes in the encoders' noise
LADDER = (TripodRung(bumps=6, height=0.05, push=(0.2, 0.5), pushes=2, slip=0.0),
          TripodRung(bumps=12, height=0.05, push=(0.2, 0.5), pushes=3, slip=0.002),
          TripodRung(bumps=20, height=0.05, push=(0.15, 0.5), pushes=4, slip=0.003))


def knob_table(indent: str = "") -> str:
    """The knobs of every rung of :data:`LADDER` as a reStructuredText table (the rung pages show it)."""
    return base.knob_table(LADDER, {"bumps": "bumps", "height": "height (m)", "pushes": "pushes",
                                    "push": "push (m)", "slip": "slip (m/s)"}, indent)


def ladder_scenario(rng: np.random.Generator, rung: TripodRung) -> TripodScenario:
    """A drive of one rung of the ladder (named "random" on the rung's env id), drawn from ``rng`` in this order:
    the heading, uniform in [-pi, pi); the bumps, each at 3.5-19 m along the path and +-2.2 m across it (no unit
    starts on one), of radius 0.3-0.6 m and height +-[height / 2, height]; the first pushed unit, then each push's
    time and distance. The drive's 20-25 s (20 m at 0.66 m/s: 30.3 s) are cut into ``pushes`` equal windows
    from 3 s, one push in each, 4 s clear of the next; each push is on the next unit in turn. No heading error
    (the paper's single-fault correction cannot see a misaligned unit)."""
    heading = float(rng.uniform(-math.pi, math.pi))
    c, s = math.cos(heading), math.sin(heading)
    bumps = []
    for _ in range(rung.bumps):
        along, across = rng.uniform(3.5, 19.0), rng.uniform(-2.2, 2.2)
        height = float(rng.choice([-1.0, 1.0]) * rng.uniform(rung.height / 2, rung.height))
        bumps.append((float(along * c - across * s), float(along * s + across * c), height,
                      float(rng.uniform(0.3, 0.6))))
    window = (25.0 - 3.0) / rung.pushes
    pushes = tuple((int(rng.integers(3)), float(3.0 + j * window + rng.uniform(0.0, window - 4.0)),
                    float(rng.uniform(*rung.push))) for j in range(rung.pushes))
    return TripodScenario("random", heading=heading, push=pushes[0], more_pushes=pushes[1:], slip=rung.slip,
                          terrain=Terrain(tuple(bumps)))


def paper_scenario() -> TripodScenario:
    """The benchmark's paper case: paper 004's scenario 2, the push (its three drives have no single one)."""
    return drive_scenario("push", np.random.default_rng(0))  # the push draws nothing


def random_scenario(rng: np.random.Generator) -> TripodScenario:
    """A seeded random mixture of every disturbance: heading error, push, slip and bumps."""
    return drive_scenario("random", rng)


def resolve_scenario(choice: Any) -> str | TripodScenario:
    """The scenario argument, checked (:func:`paragym.tasks.base.resolve_scenario`):
    a name of :data:`SCENARIOS` or a :class:`TripodScenario` that can run."""
    return base.resolve_scenario(choice, SCENARIOS, TripodScenario, validate_scenario)


def draw_scenarios(choice: Any, rngs: list[np.random.Generator], rung: TripodRung | None = None
                   ) -> list[TripodScenario]:
    """One episode's drive per generator (single env, vector env and CLI alike): a named or
    random one drawn from each generator, or the custom one once checked. On a rung of the ladder
    (``rung``, one of :data:`LADDER`) "random" is the rung's drive (:func:`ladder_scenario`)."""
    choice = resolve_scenario(choice)
    if choice == "random" and rung is not None:
        return [ladder_scenario(rng, rung) for rng in rngs]
    return [drive_scenario(choice, rng) if isinstance(choice, str) else choice for rng in rngs]


def _draw_drive(choice: Any, rng: np.random.Generator) -> TripodScenario:
    """:func:`draw_scenarios` for one generator (the name of before paragym 0.9: ``draw_drive``)."""
    return draw_scenarios(choice, [rng])[0]

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = base.renamed(__name__, {"DriveScenario": "TripodScenario", "resolve_drive": "resolve_scenario",
                                      "draw_drive": "_draw_drive", "validate_drive_scenario": "validate_scenario"})
