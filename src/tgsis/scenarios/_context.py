"""What every scenario gets: a fresh database, the report, SQL printed with its answer, a folder for files."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import psycopg
from psycopg import sql

from tgsis.db import connect, install
from tgsis.db.temporal import surfaces_at
from tgsis.errors import MissingPrivilegeError, reraise
from tgsis.temporal import EvolvingSurface

Size = Literal["small", "large"]


@dataclass(frozen=True)
class Scenario:
    """A sample application: its name, one line saying what it shows, and the function that runs it."""

    name: str
    summary: str
    run: Callable[[Context], None]


@dataclass(frozen=True)
class ScenarioResult:
    """What a scenario wrote and the figures its report gave (name -> value)."""

    name: str
    files: list[Path]
    figures: dict[str, Any]


@dataclass
class Context:
    """The scenario's database connection, report, output folder and size."""

    name: str
    conn: psycopg.Connection[Any]
    out: Callable[[str], None]
    folder: Path
    size: Size
    files: list[Path] = field(default_factory=list)
    figures: dict[str, Any] = field(default_factory=dict)

    def ask(self, question: str, query: sql.SQL | sql.Composed) -> list[tuple[Any, ...]]:
        """Print the question, the statement as psql would take it (values inlined) and its answer rows."""
        text = query.as_string(self.conn)
        with reraise():
            cursor = self.conn.execute(query)
            rows: list[tuple[Any, ...]] = cursor.fetchall()
            names = [d.name for d in cursor.description or []]
        self.conn.commit()
        self.out(f"   {question}")
        self.out(f"     {text};")
        self.out(f"     -> {', '.join(names)}: " + "; ".join(", ".join(_shown(v) for v in row) for row in rows))
        return rows

    def structure_at(self, feature_class: str, t: float, evolving: Mapping[str, EvolvingSurface]) -> None:
        """Ask for every surface of a class that exists at t in one query, and check it equals the Python snapshots.

        ``evolving`` maps each feature's name to what was stored; the figures
        ``structure_at_<t>`` (the names found) and ``sql_equals_python`` (true only
        if every structure asked for so far was equal) are kept.
        """
        rows = self.ask(
            "every surface that exists then, from one query",
            sql.SQL(
                "SELECT g.geoname AS surface, array_length(s.vertices, 1) AS vertices, "
                "array_length(s.triangles, 1) AS triangles "
                "FROM tgsis.surfaces_at({}, {}) s JOIN tgsis.geometry g USING (geoid) ORDER BY g.geoname"
            ).format(sql.Literal(feature_class), sql.Literal(t)),
        )
        from_sql = {s.name or "": s for s in surfaces_at(self.conn, feature_class, t).values()}
        expected = {name: s.at(t) for name, s in evolving.items()}
        present = sorted(name for name, s in expected.items() if s is not None)
        same = sorted(from_sql) == present and all(
            np.array_equal(from_sql[n].vertices, e.vertices) and np.array_equal(from_sql[n].cells, e.cells)
            for n in present
            for e in [expected[n]]
            if e is not None
        )
        self.out(
            f"   from Python (EvolvingSurface.at): {', '.join(present)}; "
            f"equal to SQL to the bit: {'yes' if same else 'NO'}"
        )
        self.figure(f"structure_at_{t:g}", [row[0] for row in rows])
        self.figure("sql_equals_python", same and self.figures.get("sql_equals_python", True))

    def wrote(self, paths: Sequence[Path] | Path) -> None:
        for path in [paths] if isinstance(paths, Path) else paths:
            self.files.append(path)

    def figure(self, name: str, value: Any) -> Any:
        self.figures[name] = value
        return value

    def summary_line(self) -> str:
        return ", ".join(f"{k} {_shown(v)}" for k, v in self.figures.items())


def _shown(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def fresh_database(dsn: str | None, database: str) -> str:
    """Drop and create ``database`` on the target server; return its conninfo."""
    with connect(dsn, autocommit=True) as admin:
        try:
            with reraise():
                admin.execute(sql.SQL("DROP DATABASE IF EXISTS {} WITH (FORCE)").format(sql.Identifier(database)))
                admin.execute(sql.SQL("CREATE DATABASE {}").format(sql.Identifier(database)))
        except MissingPrivilegeError as exc:
            raise MissingPrivilegeError(
                f"the demo needs a database of its own ({database}) and this role may not create one",
                hint="run it without --dsn (tgsis starts a local server), or with a DSN of a role that has CREATEDB",
            ) from exc
        return psycopg.conninfo.make_conninfo(admin.info.dsn, dbname=database)


@contextlib.contextmanager
def open_context(
    name: str, dsn: str | None, *, out: Callable[[str], None], folder: str | Path | None, size: Size
) -> Iterator[Context]:
    """A fresh database ``tgsis_demo_<name>`` with tgsis, and the output folder (created)."""
    target = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix=f"tgsis-{name}-"))
    target.mkdir(parents=True, exist_ok=True)
    conninfo = fresh_database(dsn, f"tgsis_demo_{name}")
    with psycopg.connect(conninfo) as conn:
        install(conn)
        out(f"scenario {name} ({size}) in database tgsis_demo_{name}; files go to {target}")
        yield Context(name, conn, out, target, size)
