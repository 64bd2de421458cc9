"""Reference policies and planners (imported as ``paragym.planners``)."""

from paragym.planners.base import PlanningError, Policy
from paragym.planners.grid_path import GridFieldPolicy, GridPathPlanner, GridPathPolicy
from paragym.planners.rrt_ga import RrtGaPlanner, RrtGaPolicy, RrtGaResult, RrtGaSettings

__all__ = ["GridFieldPolicy", "GridPathPlanner", "GridPathPolicy", "PlanningError", "Policy", "RrtGaPlanner",
           "RrtGaPolicy", "RrtGaResult", "RrtGaSettings"]
