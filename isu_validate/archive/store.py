"""Every evaluated test is committed to SQLite (WAL, synchronous=FULL) before the search
moves on, so a killed run loses nothing and a resumed one evaluates nothing twice."""
from __future__ import annotations

import json
import sqlite3
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Iterator

SCHEMA_VERSION = 1


@dataclass
class TestRecord:
    test_id: str                 # "g{generation:04d}-i{index:03d}"
    generation: int
    index: int
    algorithm: str
    seed: int
    scene_key: str
    scene: dict                  # full scene (latent inactive values included)
    canonical: dict              # active features only
    f_div: float = 0.0
    image: str | None = None     # relative to the run directory
    sut_raw: str | None = None
    answers: dict | None = None
    caption: str | None = None
    fitness: dict = field(default_factory=dict)
    primary: float | None = None
    failed: bool = False
    sut_error: str | None = None
    render_error: str | None = None
    timings: dict = field(default_factory=dict)
    details: dict = field(default_factory=dict)
    created: float = 0.0

    @property
    def render_s(self) -> float | None:
        return self.timings.get("render_s")

    @property
    def sut_s(self) -> float | None:
        return self.timings.get("sut_s")

    @property
    def errored(self) -> bool:
        return bool(self.sut_error or self.render_error)

    @property
    def occluded(self) -> list[str]:
        """Features the frame showed too little of to be judged (left out of the fitness)."""
        return list(self.details.get("occluded", []))

    @property
    def visibility(self) -> dict[str, float]:
        """Visible share of each feature that shows something (see isu_validate/render/visibility.py)."""
        return dict(self.details.get("visibility", {}))


_JSON_FIELDS = ("scene", "canonical", "answers", "fitness", "timings", "details")
_COLUMNS = [f for f in TestRecord.__dataclass_fields__]


class Archive:
    def __init__(self, path: Path):
        self.path = Path(path)
        self.db = sqlite3.connect(self.path, isolation_level=None, timeout=30)
        self.db.execute("PRAGMA journal_mode=WAL")
        self.db.execute("PRAGMA synchronous=FULL")
        self.db.execute(f"CREATE TABLE IF NOT EXISTS tests ({', '.join(self._column_defs())})")
        self.db.execute("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)")
        self.db.execute("INSERT OR IGNORE INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))

    @staticmethod
    def _column_defs() -> list[str]:
        defs = []
        for name in _COLUMNS:
            kind = {"generation": "INTEGER", "index": "INTEGER", "seed": "INTEGER", "failed": "INTEGER",
                    "f_div": "REAL", "primary": "REAL", "created": "REAL"}.get(name, "TEXT")
            defs.append(f'"{name}" {kind}' + (" PRIMARY KEY" if name == "test_id" else ""))
        return defs

    def add(self, record: TestRecord) -> None:
        """Commit one test durably; a second commit of the same test_id is refused."""
        record.created = record.created or time.time()
        row = asdict(record)
        values = [json.dumps(row[c]) if c in _JSON_FIELDS else row[c] for c in _COLUMNS]
        placeholders = ", ".join("?" for _ in _COLUMNS)
        quoted = ", ".join(f'"{c}"' for c in _COLUMNS)
        self.db.execute(f"INSERT INTO tests ({quoted}) VALUES ({placeholders})", values)

    def get(self, test_id: str) -> TestRecord | None:
        cur = self.db.execute('SELECT * FROM tests WHERE test_id = ?', (test_id,))
        row = cur.fetchone()
        return self._record(cur, row) if row else None

    def __iter__(self) -> Iterator[TestRecord]:
        cur = self.db.execute('SELECT * FROM tests ORDER BY generation, "index"')
        for row in cur.fetchall():
            yield self._record(cur, row)

    def __len__(self) -> int:
        return self.db.execute("SELECT COUNT(*) FROM tests").fetchone()[0]

    @staticmethod
    def _record(cur, row) -> TestRecord:
        data = dict(zip([d[0] for d in cur.description], row))
        for c in _JSON_FIELDS:
            data[c] = json.loads(data[c]) if data[c] is not None else None
        data["failed"] = bool(data["failed"])
        data["fitness"] = data["fitness"] or {}
        data["timings"] = data["timings"] or {}
        data["details"] = data["details"] or {}
        return TestRecord(**data)

    def set_meta(self, key: str, value: Any) -> None:
        self.db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, json.dumps(value)))

    def get_meta(self, key: str, default: Any = None) -> Any:
        row = self.db.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return json.loads(row[0]) if row else default

    def close(self) -> None:
        self.db.close()


def read_records(path: Path) -> list[TestRecord]:
    """Every test of an archive file, in run order; the file is closed again."""
    archive = Archive(path)
    try:
        return list(archive)
    finally:
        archive.close()
