"""Baseline policies (imported as ``paragym.baselines``): the trivial ones every
learned agent must beat; the Stable-Baselines3 agents join them here."""

from paragym.baselines.simple import RandomPolicy, ZeroPolicy

__all__ = ["RandomPolicy", "ZeroPolicy"]
