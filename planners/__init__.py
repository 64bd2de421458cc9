"""Reference policies and planners (imported as ``paragym.planners``)."""

from paragym.planners.base import Policy
from paragym.planners.grid_path import GridPathPlanner, GridPathPolicy, PlanningError

__all__ = ["GridPathPlanner", "GridPathPolicy", "PlanningError", "Policy"]
