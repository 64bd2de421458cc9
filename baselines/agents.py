"""Agents from outside paragym: what identifies them, and how they are loaded.

An agent is a factory ``factory(env, seed) -> policy`` (a class or a
function) whose policy has ``reset(obs, info)`` and ``act(obs, info)``.
Its leaderboard rows must never be taken for another agent's, so its
producer (:func:`identity`) holds whatever defines its behaviour:

* its qualified name (``module.Class``);
* the SHA-256 of the source file of the module that defines it (an edit to
  the file re-runs its episodes; the run says why);
* its parameters: those given to :func:`~paragym.baselines.policies.register_policy`,
  the arguments a ``functools.partial`` binds, an instance's attributes.

paragym's own policies are identified by the package version, which is part
of every row's key, so their producers name no source. A factory whose
source cannot be read (typed into an interactive session) gets a producer
that no other run can match: its rows are never reused, and
:func:`unreadable` says so.

:func:`load_agent` reads ``path/to/file.py:Factory`` or ``package.module:attr``
(``paragym leaderboard --agent``). A file is imported as a module, so its
code runs: point it only at agents you trust, as with any Python you run.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
import traceback
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["AgentFile", "identity", "load_agent", "sha256_of_file", "source_sha256", "unreadable"]

#: one value per process for factories whose source cannot be read: rows made with it are never matched again
_UNREADABLE = f"unreadable source (run {uuid.uuid4().hex[:12]}): its rows are never reused"


def sha256_of_file(path: str | Path) -> str:
    """The SHA-256 of the file at ``path`` (read a MiB at a time)."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _defining(factory: Any) -> tuple[Any, dict[str, Any]]:
    """The function or class whose code acts, and the parameters bound to it (a partial's, an instance's)."""
    params: dict[str, Any] = {}
    while isinstance(factory, functools.partial):
        params = {"args": [repr(a) for a in factory.args], **{k: repr(v) for k, v in factory.keywords.items()},
                  **({"inner": params} if params else {})}
        factory = factory.func
    if inspect.isfunction(factory) or inspect.ismethod(factory) or inspect.isclass(factory):
        return factory, params
    state = getattr(factory, "__dict__", None)
    if state:
        params = {**params, "attributes": {k: repr(v) for k, v in sorted(state.items())}}
    return type(factory), params


def _is_paragym(code: Any) -> bool:
    return (getattr(code, "__module__", "") or "").split(".")[0] == "paragym"


def source_sha256(code: Any) -> str | None:
    """The SHA-256 of the source file of the module that defines ``code``, or
    None when there is none to read (an interactive session, a built-in)."""
    try:
        path = inspect.getsourcefile(code)
    except TypeError:
        path = None
    if path is None or not Path(path).is_file():
        try:  # a class or function typed into a notebook: its own lines, where the session kept them
            return hashlib.sha256(inspect.getsource(code).encode()).hexdigest()
        except (OSError, TypeError):
            return None
    return sha256_of_file(path)


def identity(factory: Callable[..., Any], params: dict[str, Any] | None = None) -> dict[str, Any]:
    """What makes ``factory``'s actions: ``{"policy": qualified name,
    "params": ...}``, and for an agent from outside paragym the SHA-256 of
    its source (``"source_sha256"``, or ``"source"`` saying it could not be
    read)."""
    if isinstance(factory, AgentFile):  # named by the file's name: its hash says which file, on any machine
        return {"policy": f"{Path(factory.path).name}:{factory.attr}", "params": dict(params or {}),
                "source_sha256": factory.sha256}
    own = factory if inspect.isfunction(factory) or inspect.ismethod(factory) else type(factory)
    if _is_paragym(own):  # paragym's own: the version in every row's key says which code; params say the rest
        return {"policy": f"{own.__module__}.{own.__qualname__}", "params": dict(params or {})}
    code, bound = _defining(factory)
    found = source_sha256(code)
    return {"policy": f"{code.__module__}.{code.__qualname__}", "params": {**bound, **(params or {})},
            **({"source_sha256": found} if found else {"source": _UNREADABLE})}


def unreadable(producer: dict[str, Any]) -> bool:
    """Whether a producer comes from a factory whose source could not be read."""
    return str(producer.get("source", "")).startswith("unreadable source")


@dataclass(frozen=True)
class AgentFile:
    """``attr`` of the Python file at ``path``, which had SHA-256 ``sha256``
    when it was named: a factory that can be sent to worker processes and Ray
    tasks (each imports the file once, and only if it is still that file)."""

    path: str
    attr: str
    sha256: str

    def __call__(self, env: Any, seed: int) -> Any:
        return self.target(env, seed)

    @property
    def target(self) -> Any:
        """The factory the file defines."""
        return _file_attr(self.path, self.attr, self.sha256)


@functools.lru_cache(maxsize=32)
def _file_attr(path: str, attr: str, sha256: str) -> Any:
    p = Path(path)
    if not p.is_file() or sha256_of_file(p) != sha256:
        raise ValueError(f"agent file {p} changed (or went) since the leaderboard listed it (SHA-256 "
                         f"{sha256[:12]}): its episodes would not be the ones its rows name; run again")
    name = f"paragym_agent_{sha256[:16]}"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, p)
        if spec is None or spec.loader is None:
            raise ValueError(f"agent file {p} cannot be imported as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # so that classes defined in it pickle within this process
        try:
            spec.loader.exec_module(module)
        except SyntaxError as exc:  # one line that names the file and the place, no traceback of the import
            del sys.modules[name]
            raise ValueError(f"agent file {p}, line {exc.lineno}: {type(exc).__name__}: {exc.msg}") from None
        except Exception as exc:
            del sys.modules[name]
            lines = [f.lineno for f in traceback.extract_tb(exc.__traceback__) if Path(f.filename) == p]
            where = f", line {lines[-1]}" if lines else ""
            raise ValueError(f"agent file {p}{where}: importing it raised {type(exc).__name__}: {exc}") from None
    if not hasattr(module, attr):
        raise ValueError(f"agent file {p} has no {attr!r}; it defines "
                         f"{', '.join(n for n in vars(module) if not n.startswith('_')) or 'nothing public'}")
    factory = getattr(module, attr)
    if not callable(factory):
        raise ValueError(f"{p}:{attr} is not callable as factory(env, seed)")
    return factory


def load_agent(text: str) -> tuple[str, Callable[..., Any]]:
    """``text`` as ``[NAME=]path/to/file.py:ATTR`` or ``[NAME=]package.module:ATTR``
    -> (the policy's name, its factory). The name defaults to ATTR. A
    ValueError says what is wrong with ``text``."""
    name, _, target = text.rpartition("=") if "=" in text.split(":")[0] else ("", "", text)
    where, sep, attr = target.rpartition(":")
    if not sep or not where or not re.fullmatch(r"[A-Za-z_]\w*", attr):
        raise ValueError(f"--agent {text!r}: expected path/to/file.py:Factory or package.module:Factory "
                         f"(optionally NAME=... in front)")
    name = name or attr
    if where.endswith(".py") or "/" in where or Path(where).is_file():
        p = Path(where).resolve()
        if not p.is_file():
            raise ValueError(f"--agent {text!r}: no file {where}")
        factory: Callable[..., Any] = AgentFile(str(p), attr, sha256_of_file(p))
        _file_attr(factory.path, attr, factory.sha256)  # fails now, not in the first episode
        return name, factory
    try:
        module = importlib.import_module(where)
    except ImportError as exc:
        raise ValueError(f"--agent {text!r}: cannot import {where}: {exc}") from exc
    if not hasattr(module, attr):
        raise ValueError(f"--agent {text!r}: module {where} has no {attr!r}")
    factory = getattr(module, attr)
    if not callable(factory):
        raise ValueError(f"--agent {text!r}: {where}:{attr} is not callable as factory(env, seed)")
    return name, factory
