"""An env's mechanism written as a model file: the env made in dynamic fidelity, its scene exported.

The writing itself is :mod:`paragym.sim.export`'s, from the scene alone; this module makes the env (Gymnasium's
``make``, the registered id) and hands its scene over. ``paragym export`` is :func:`write`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import gymnasium as gym

from paragym.sim.export import FORMATS, check_mjcf, check_urdf, mjcf, urdf

__all__ = ["dynamic_env", "scene_of", "write"]


def dynamic_env(env_id: str) -> Any:
    """``env_id`` in dynamic fidelity with its default dynamics, after ``reset(seed=0)``; its scene is
    :func:`scene_of` it. The caller closes it."""
    env = gym.make(env_id, fidelity="dynamic")
    env.reset(seed=0)
    return env


def scene_of(env: Any) -> Any:
    """The PyBullet scene of an env in dynamic fidelity (``env.unwrapped.world.scene``)."""
    world = getattr(env.unwrapped, "world", None)
    if world is None or not hasattr(world, "scene"):
        raise ValueError(f"{env.unwrapped.spec.id if env.unwrapped.spec else env} has no dynamic scene: make it "
                         'with fidelity="dynamic"')
    return world.scene


def write(env_id: str, fmt: str, out: str | Path,
          overwrite: bool = False) -> tuple[list[Path], dict[str, float] | None]:
    """Write ``env_id``'s mechanism as ``fmt`` ("mjcf" or "urdf") at its pose after ``reset(seed=0)`` to ``out``:
    a file (its suffix is the format's, added when missing) or a folder (an existing one, or a path ending in a
    separator), where the file is named after the env. The MJCF stands on its own
    (:func:`~paragym.sim.export.mjcf`'s ``home``); the URDF's sidecar, beside it, holds the same pose. An existing
    file is refused unless ``overwrite``. Returns the paths written and, where ``mujoco`` is installed, the files
    checked against the scene (:func:`~paragym.sim.export.check_mjcf`, :func:`~paragym.sim.export.check_urdf`;
    None without ``mujoco``)."""
    import importlib.util
    import os

    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}; got {fmt!r}")
    path = Path(out)
    if path.is_dir() or str(out).endswith((os.sep, "/")):
        path = path / (env_id.split("/")[-1] + FORMATS[fmt])
    elif path.suffix != FORMATS[fmt]:
        path = path.with_name(path.name + FORMATS[fmt])
    paths = [path] + ([path.with_name(path.name + ".loops.json")] if fmt == "urdf" else [])
    existing = [str(p) for p in paths if p.exists()]
    if existing and not overwrite:
        raise FileExistsError(f"{', '.join(existing)} exists already: choose another --out, or pass --overwrite")
    env = dynamic_env(env_id)
    try:
        scene, model = scene_of(env), env_id.split("/")[-1]
        checks = importlib.util.find_spec("mujoco") is not None
        if fmt == "mjcf":
            text = mjcf(scene, model, home=True)
            texts, gaps = [text], check_mjcf(scene, text) if checks else None
        else:
            text, sidecar = urdf(scene, model)
            texts, gaps = [text, json.dumps(sidecar, indent=1) + "\n"], check_urdf(scene, text, sidecar) if checks \
                else None
    finally:
        env.close()
    path.parent.mkdir(parents=True, exist_ok=True)
    for p, text in zip(paths, texts, strict=True):
        p.write_text(text)
    return paths, gaps
