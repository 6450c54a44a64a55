"""What every scenario gets: a fresh database, the report, SQL printed with its answer, a folder for files."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import psycopg
from psycopg import sql

from tgsis.db import connect, install
from tgsis.errors import MissingPrivilegeError, reraise

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


def _fresh_database(dsn: str | None, database: str) -> str:
    """Drop and create ``database`` on the target server; return its conninfo."""
    with connect(dsn, autocommit=True) as admin:
        try:
            with reraise():
                admin.execute(sql.SQL("DROP DATABASE IF EXISTS {} WITH (FORCE)").format(sql.Identifier(database)))
                admin.execute(sql.SQL("CREATE DATABASE {}").format(sql.Identifier(database)))
        except MissingPrivilegeError as exc:
            raise MissingPrivilegeError(
                f"the scenario needs a database of its own ({database}) and this role may not create one",
                hint="run it without --dsn (tgsis starts a local server), or with a DSN of a role that has CREATEDB",
            ) from exc
        return psycopg.conninfo.make_conninfo(admin.info.dsn, dbname=database)


@contextlib.contextmanager
def open_context(name: str, dsn: str | None, *, out: Callable[[str], None], folder: str | Path | None,
                 size: Size) -> Iterator[Context]:
    """A fresh database ``tgsis_demo_<name>`` with tgsis, and the output folder (created)."""
    target = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix=f"tgsis-{name}-"))
    target.mkdir(parents=True, exist_ok=True)
    conninfo = _fresh_database(dsn, f"tgsis_demo_{name}")
    with psycopg.connect(conninfo) as conn:
        install(conn)
        out(f"scenario {name} ({size}) in database tgsis_demo_{name}; files go to {target}")
        yield Context(name, conn, out, target, size)
