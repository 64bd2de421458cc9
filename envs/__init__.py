"""paragym environments (imported as ``paragym.envs``); one Gymnasium env per task."""

from paragym.envs.capaman import CaPaManCollisionFreeEnv
from paragym.tasks.capaman import CaPaManScenario, paper_scenario, random_scenario

__all__ = ["CaPaManCollisionFreeEnv", "CaPaManScenario", "paper_scenario", "random_scenario"]
