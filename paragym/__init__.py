"""paragym: a benchmark for motion planning of parallel manipulators.

Importing ``paragym`` registers its environments with Gymnasium::

    import gymnasium as gym
    import paragym  # noqa: F401
    env = gym.make("paragym/CaPaManCollisionFree-v0")
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.8.0"

#: env id -> (entry point, max episode steps, one-line description)
ENVIRONMENTS: dict[str, tuple[str, int, str]] = {
    "paragym/CaPaManCollisionFree-v0": (
        "paragym.envs.capaman:CaPaManCollisionFreeEnv", 400,
        "CaPaMan 3-DOF: tour T.C.1->2->3->1 around obstacles, whole manipulator collision-free (paper 000)",
    ),
    "paragym/CaPaManCollisionFree-v1": (
        "paragym.envs.capaman:CaPaManCollisionFreeV1Env", 400,
        "CaPaMan v1: the v0 tour with goal-relative observations, a clearance look-ahead and a time penalty",
    ),
    "paragym/HybridSingularityFree-v0": (
        "paragym.envs.hybrid:HybridSingularityFreeEnv", 100,
        "hexapod + tripod (9 actuators): polynomial path without singular poses or leg-limit violations (paper 002)",
    ),
    "paragym/HybridSingularityFree-v1": (
        "paragym.envs.hybrid:HybridSingularityFreeV1Env", 100,
        "hybrid v1: the v0 path with the end pose P1, and P1 solved at the current split, in the observation",
    ),
    "paragym/HybridSingularityFree-v2": (
        "paragym.envs.hybrid:HybridSingularityFreeV2Env", 100,
        "hybrid v2: v1's task; in dynamic fidelity E's orientation is tracked too and a broken mechanism fails",
    ),
    "paragym/Orthoglide2PRRKappa-v0": (
        "paragym.envs.orthoglide:Orthoglide2PRRKappaEnv", 1000,
        "2PRR Orthoglide + translating table: track a path, keep the condition number of J low (paper 003)",
    ),
    "paragym/Orthoglide2PRRKappa-v1": (
        "paragym.envs.orthoglide:Orthoglide2PRRKappaV1Env", 1000,
        "2PRR v1: the v0 task, with success that requires tracking in every action mode and fidelity",
    ),
    "paragym/MobileTripodOdometry-v0": (
        "paragym.envs.mobile_tripod:MobileTripodOdometryEnv", 700,
        "mobile tripod: estimate the three drive units under slip from odometry and leg encoders (paper 004)",
    ),
    "paragym/MobileTripodOdometry-v1": (
        "paragym.envs.mobile_tripod:MobileTripodOdometryV1Env", 700,
        "mobile tripod v1: per unit, how far to trust the encoders' correction of the odometry (paper 004)",
    ),
    "paragym/MobileTripodOdometry-v2": (
        "paragym.envs.mobile_tripod:MobileTripodOdometryV2Env", 700,
        "mobile tripod v2: v1's task, where a folded mechanism (a leg past horizontal) ends the episode as a failure",
    ),
}

#: env id -> the native vector env (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``)
VECTOR_ENTRY_POINTS: dict[str, str] = {
    "paragym/CaPaManCollisionFree-v0": "paragym.envs.capaman:CaPaManCollisionFreeVectorEnv",
    "paragym/CaPaManCollisionFree-v1": "paragym.envs.capaman:CaPaManCollisionFreeV1VectorEnv",
    "paragym/Orthoglide2PRRKappa-v0": "paragym.envs.orthoglide:Orthoglide2PRRKappaVectorEnv",
    "paragym/Orthoglide2PRRKappa-v1": "paragym.envs.orthoglide:Orthoglide2PRRKappaV1VectorEnv",
    "paragym/HybridSingularityFree-v0": "paragym.envs.hybrid:HybridSingularityFreeVectorEnv",
    "paragym/HybridSingularityFree-v1": "paragym.envs.hybrid:HybridSingularityFreeV1VectorEnv",
    "paragym/HybridSingularityFree-v2": "paragym.envs.hybrid:HybridSingularityFreeV2VectorEnv",
    "paragym/MobileTripodOdometry-v0": "paragym.envs.mobile_tripod:MobileTripodOdometryVectorEnv",
    "paragym/MobileTripodOdometry-v1": "paragym.envs.mobile_tripod:MobileTripodOdometryV1VectorEnv",
    "paragym/MobileTripodOdometry-v2": "paragym.envs.mobile_tripod:MobileTripodOdometryV2VectorEnv",
}

for _env_id, (_entry, _steps, _doc) in ENVIRONMENTS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point=_entry, max_episode_steps=_steps,
                 vector_entry_point=VECTOR_ENTRY_POINTS.get(_env_id))


def check_env_id(env_id: str) -> str:
    """The full id of a registered paragym env (the ``paragym/`` prefix may be
    left out), or a ValueError listing the registered ids."""
    if not isinstance(env_id, str):
        raise ValueError(f"env id must be a string; got {env_id!r}")
    full = env_id if env_id.startswith("paragym/") else f"paragym/{env_id}"
    if full not in ENVIRONMENTS:
        raise ValueError(f"unknown env id {env_id!r}; registered: {', '.join(ENVIRONMENTS)}")
    return full
