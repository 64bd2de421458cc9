"""The leaderboard's results: one SQLite file, one row per episode.

Rows are keyed by (env, policy, seed, episode, paragym version, producer)
and each is committed as soon as its episode finishes, so an interrupted
run loses at most the episodes in flight and a rerun skips what is already
there. The producer (:meth:`paragym.baselines.policies.PolicySpec.producer`)
is what made the row: a model file's SHA-256, a planner's parameters. A
retrained model or a changed planner is a new producer: its episodes are
run again, never mixed with the old ones, which stay in the file. A
file written by another paragym version (or not a paragym database at all)
is refused with a clear error and left untouched: its numbers would not be
comparable, and the ``--db`` option takes a new file.
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import paragym

__all__ = ["SCHEMA_VERSION", "DynamicRow", "EpisodeRow", "ResultStore", "ValidationRow", "producer_id"]

SCHEMA_VERSION = "3"  # 3: the dynamic fidelity's episodes (paragym 0.6.0)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS episodes (
    env TEXT NOT NULL, policy TEXT NOT NULL, seed INTEGER NOT NULL, episode INTEGER NOT NULL,
    version TEXT NOT NULL, kind TEXT NOT NULL, episode_return REAL NOT NULL, length INTEGER NOT NULL,
    success INTEGER NOT NULL, metrics TEXT NOT NULL, wall_seconds REAL NOT NULL, finished_at REAL NOT NULL,
    producer TEXT NOT NULL, PRIMARY KEY (env, policy, seed, episode, version, producer));
CREATE TABLE IF NOT EXISTS validations (
    env TEXT NOT NULL, policy TEXT NOT NULL, version TEXT NOT NULL, passed INTEGER NOT NULL,
    summary TEXT NOT NULL, producer TEXT NOT NULL, PRIMARY KEY (env, policy, version, producer));
CREATE TABLE IF NOT EXISTS dynamic (
    env TEXT NOT NULL, policy TEXT NOT NULL, scenario TEXT NOT NULL, seed INTEGER NOT NULL, version TEXT NOT NULL,
    producer TEXT NOT NULL, episode_return REAL NOT NULL, success INTEGER NOT NULL, metrics TEXT NOT NULL,
    kf_passed INTEGER NOT NULL, kf TEXT NOT NULL, wall_seconds REAL NOT NULL,
    PRIMARY KEY (env, policy, scenario, seed, version, producer));
"""


def producer_id(producer: str) -> str:
    """A producer in 16 hex digits (the first of its SHA-256): how the CSVs name it on every line."""
    return hashlib.sha256(producer.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class EpisodeRow:
    """One evaluated episode. ``metrics``: the task's own measures (floats)."""

    env: str
    policy: str
    seed: int
    episode: int
    kind: str
    episode_return: float
    length: int
    success: bool
    metrics: dict[str, float] = field(default_factory=dict)
    wall_seconds: float = 0.0
    version: str = paragym.__version__
    producer: str = ""

    @property
    def key(self) -> tuple[str, str, int, int, str, str]:
        return (self.env, self.policy, self.seed, self.episode, self.version, self.producer)


@dataclass(frozen=True)
class DynamicRow:
    """One episode in the dynamic fidelity: the task's measures, and the KF
    verdict on what the policy executed against what it commanded (``kf``:
    the worst component and the body's largest distance from its command)."""

    env: str
    policy: str
    scenario: str
    seed: int
    episode_return: float
    success: bool
    metrics: dict[str, float]
    kf_passed: bool
    kf: dict[str, Any]
    wall_seconds: float = 0.0
    version: str = paragym.__version__
    producer: str = ""

    @property
    def key(self) -> tuple[str, str, str, int, str, str]:
        return (self.env, self.policy, self.scenario, self.seed, self.version, self.producer)

    @property
    def engine(self) -> str:
        """The physics engine it ran in: "pybullet", unless its producer names another
        (:func:`paragym.baselines.leaderboard.suite.dynamic_producer`)."""
        return "mujoco" if self.producer and "engine" in json.loads(self.producer) else "pybullet"


@dataclass(frozen=True)
class ValidationRow:
    """The KF validation of a task's reference plan (its bench's ``validated_plan``): the verdict and what
    the check found, for the reference of ``env`` made by ``producer``."""

    env: str
    policy: str
    passed: bool
    summary: dict[str, Any]
    producer: str = ""


#: SQLite's application id of a paragym results file ("PGYM"): a file without it was not made by paragym
APPLICATION_ID = 0x5047594D


class ResultStore:
    """The SQLite file at ``path`` (made, with its folder, if missing).

    An existing file is opened only if paragym made it (its SQLite
    application id), for this version and schema, and it passes SQLite's
    ``quick_check``; anything else is refused with a ValueError naming the
    file, before a byte is written to it. A file that cannot be created or
    written (a read-only folder, a path through a file) is a ValueError too.
    """

    def __init__(self, path: str | Path, version: str = paragym.__version__) -> None:
        self.path, self.version = Path(path), version
        try:
            if self.path.exists():
                self._check_existing()
                self.db = sqlite3.connect(self.path)
                self.db.execute("PRAGMA user_version").fetchone()  # opens it for writing now, not mid-run
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self.db = sqlite3.connect(self.path)
                with self.db:
                    self.db.execute(f"PRAGMA application_id = {APPLICATION_ID}")
                    self.db.executescript(_SCHEMA)
                    self.db.execute("INSERT INTO meta VALUES ('schema', ?)", (SCHEMA_VERSION,))
                    self.db.execute("INSERT INTO meta VALUES ('paragym_version', ?)", (version,))
        except (sqlite3.Error, OSError) as exc:
            raise ValueError(f"cannot use {self.path} as the results database: {exc} (choose another file with "
                             f"--db)") from exc

    def _check_existing(self) -> None:
        """Refuse (ValueError) a file that is not this version's paragym database, before writing anything."""
        try:
            db = sqlite3.connect(f"file:{self.path}?mode=ro", uri=True)
            try:
                app = db.execute("PRAGMA application_id").fetchone()[0]
                meta = dict(db.execute("SELECT key, value FROM meta").fetchall()) if app == APPLICATION_ID or (
                    db.execute("SELECT 1 FROM sqlite_master WHERE name = 'meta'").fetchone()) else {}
                check = db.execute("PRAGMA quick_check").fetchone()[0] if app == APPLICATION_ID else "ok"
            finally:
                db.close()
        except sqlite3.DatabaseError as exc:
            raise ValueError(f"{self.path} is not a paragym results database, or it is damaged ({exc}); choose "
                             f"another file with --db") from exc
        if "paragym_version" in meta and (meta.get("schema") != SCHEMA_VERSION or
                                          meta.get("paragym_version") != self.version):
            raise ValueError(f"{self.path} holds results of paragym {meta.get('paragym_version', '?')} (schema "
                             f"{meta.get('schema', '?')}); this is paragym {self.version} (schema {SCHEMA_VERSION}). "
                             f"Results of different versions are not comparable: use --db for a new file")
        if app != APPLICATION_ID:
            raise ValueError(f"{self.path} is not a paragym results database (paragym writes only to files it "
                             f"made); choose another file with --db")
        if check != "ok":
            raise ValueError(f"{self.path} is damaged (SQLite's quick_check: {check}); choose another file with --db")

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def done_keys(self) -> set[tuple[str, str, int, int, str, str]]:
        """The keys of every stored episode."""
        return set(self.db.execute("SELECT env, policy, seed, episode, version, producer FROM episodes").fetchall())

    def add(self, row: EpisodeRow) -> None:
        """Store one episode now (a key already stored is kept as it was)."""
        self.add_all([row], [])

    def add_all(self, rows: list[EpisodeRow], dynamic: list[DynamicRow]) -> None:
        """Store many rows in one transaction (keys already stored are kept as they were)."""
        with self.db:
            self.db.executemany("INSERT OR IGNORE INTO episodes VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?)",
                                [(r.env, r.policy, r.seed, r.episode, r.version, r.kind, float(r.episode_return),
                                  int(r.length), int(r.success), json.dumps(r.metrics, sort_keys=True),
                                  float(r.wall_seconds), time.time(), r.producer) for r in rows])
            self.db.executemany("INSERT OR IGNORE INTO dynamic VALUES (?,?,?,?,?,?,?,?,?,?,?,?)",
                                [(r.env, r.policy, r.scenario, r.seed, r.version, r.producer,
                                  float(r.episode_return), int(r.success), json.dumps(r.metrics, sort_keys=True),
                                  int(r.kf_passed), json.dumps(r.kf, sort_keys=True), float(r.wall_seconds))
                                 for r in dynamic])

    def rows(self, env: str | None = None) -> list[EpisodeRow]:
        """This version's episodes (of ``env``), in key order."""
        query = ("SELECT env, policy, seed, episode, kind, episode_return, length, success, metrics, wall_seconds, "
                 "version, producer FROM episodes WHERE version = ?" + (" AND env = ?" if env else "") +
                 " ORDER BY env, policy, seed, episode, producer")
        args = (self.version, env) if env else (self.version,)
        return [EpisodeRow(e, p, s, k, kind, r, n, bool(ok), json.loads(m), w, v, prod)
                for e, p, s, k, kind, r, n, ok, m, w, v, prod in self.db.execute(query, args)]

    def dynamic_keys(self) -> set[tuple[str, str, str, int, str, str]]:
        """The keys of every stored dynamic-fidelity episode."""
        return set(self.db.execute("SELECT env, policy, scenario, seed, version, producer FROM dynamic").fetchall())

    def add_dynamic(self, row: DynamicRow) -> None:
        """Store one dynamic-fidelity episode now (a key already stored is kept as it was)."""
        self.add_all([], [row])

    def dynamic_rows(self) -> list[DynamicRow]:
        """This version's dynamic-fidelity episodes, in key order."""
        query = ("SELECT env, policy, scenario, seed, episode_return, success, metrics, kf_passed, kf, wall_seconds, "
                 "version, producer FROM dynamic WHERE version = ? ORDER BY env, policy, scenario, seed, producer")
        return [DynamicRow(e, p, sc, s, r, bool(ok), json.loads(m), bool(kp), json.loads(kf), w, v, prod)
                for e, p, sc, s, r, ok, m, kp, kf, w, v, prod in self.db.execute(query, (self.version,))]

    def set_validation(self, env: str, policy: str, passed: bool, summary: dict[str, Any], producer: str = "") -> None:
        with self.db:
            self.db.execute("INSERT OR REPLACE INTO validations VALUES (?,?,?,?,?,?)",
                            (env, policy, self.version, int(passed), json.dumps(summary, sort_keys=True), producer))

    def validation(self, env: str, policy: str, producer: str = "") -> dict[str, Any] | None:
        """The stored verdict ``{"passed": bool, **summary}`` of ``producer``'s policy, or None."""
        got = self.db.execute("SELECT passed, summary FROM validations WHERE env=? AND policy=? AND version=? AND "
                              "producer=?", (env, policy, self.version, producer)).fetchone()
        return None if got is None else {"passed": bool(got[0]), **json.loads(got[1])}
