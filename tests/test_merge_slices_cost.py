"""The Python merge of a surface at instants reads what changed, not the whole object (issue 39, docs/merge.md).

``tgsis.merge_version`` of a model-2 object changed on both sides reads the
storage rows the sides' revisions wrote or closed, and of the instants those
touch only the change's one-ring (the cells on the changed vertices, their
corners, those vertices' property rows), as model 1's ``read_merge_change``:
the instants no side touched are alike on all three sides and would write
nothing, and neither would the rest of a touched instant. Counted, not timed:
the rows the merge decodes from the server (``columns_out_all``) follow the
change, not the touched instants' size, and the result is the same union of
both edits, bit for bit, the untouched instants and rows as they were.
"""

from __future__ import annotations

import re
import tempfile
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tgsis.db import _merge_states
from tgsis.db._transfer import columns_out_all
from tgsis.db.classes import list_feature_classes
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]

SIDE = 10
TIMES = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0)
NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)
CHILD_SHIFT = (0.125, -3.3, 7.77)
PARENT_SHIFT = (-1.1, 0.0, -2.9)


def _grid(i: int) -> tuple[np.ndarray, np.ndarray]:
    """A SIDE x SIDE grid, curved, other at each instant (full mantissas), and its triangles."""
    x, y = np.meshgrid(np.arange(SIDE, dtype=np.float64), np.arange(SIDE, dtype=np.float64))
    z = np.sin(x / 3.0) * np.cos(y / 7.0) + (i + 1) / 3.0
    vertices = np.stack([x.ravel() * 1.1, y.ravel() / 3.0, z.ravel()], axis=1)
    cells = []
    for r in range(SIDE - 1):
        for c in range(SIDE - 1):
            a = r * SIDE + c
            cells += [(a, a + 1, a + SIDE), (a + 1, a + SIDE + 1, a + SIDE)]
    return vertices, np.asarray(cells, dtype=np.int64)


def _porosity(i: int) -> np.ndarray:
    return np.linspace(0.1, 0.3, SIDE * SIDE) + i / 7.0


@pytest.fixture
def series(conn: Conn) -> int:
    """A model-2 surface at 8 instants (a vertex property, a per-instant property) in DEFAULT, version e1 on it."""
    return _series(conn, TIMES)


def _series(conn: Conn, times: tuple[float, ...]) -> int:
    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    surfaces = []
    for i in range(len(times)):
        vertices, cells = _grid(i)
        surfaces.append(tgsis.Surface(vertices, cells, vertex_properties={"porosity": _porosity(i)}))
    throw = np.asarray([10.0 * (i + 1) for i in range(len(times))])
    geoid = tgsis.insert_feature(
        conn, "horizons", SurfaceSeries(np.asarray(times), surfaces, properties={"throw": throw})
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def _move(conn: Conn, version: str, geoid: int, t: float, ids: Any, shift: tuple[float, float, float]) -> None:
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.times_vrtx SET x = x + %s, y = y + %s, z = z + %s"
            " WHERE geoid = %s AND times = %s AND vrtxid = ANY(%s)",
            (*shift, geoid, t, [int(i) for i in np.asarray(ids)]),
        )
    conn.commit()


def _shifted(base: np.ndarray, ids: Any, shift: tuple[float, float, float]) -> np.ndarray:
    out = base.copy()
    out[np.asarray(ids)] += np.asarray(shift)  # the same float additions as the UPDATEs
    return out


def _rows_decoded(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """A counter of the rows the merge's reads of the states decode (every table's, every request's)."""
    counted = [0]
    real = columns_out_all

    def counting(conn: Conn, requests: Any) -> Any:
        read = real(conn, requests)
        counted[0] += sum(len(columns[0]) for columns in read)
        return read

    monkeypatch.setattr(_merge_states, "columns_out_all", counting)
    return counted


def _state(conn: Conn, version: str, geoid: int) -> dict[str, Any]:
    """Everything a psql user reads of the object: per instant the vertices (bits), cells, porosity (bits), throw."""
    out: dict[str, Any] = {}
    fc = next(c for c in list_feature_classes(conn) if c.name == "horizons")
    vertex_table = fc.property_table("VERTEX")
    assert vertex_table is not None and fc.protable is not None
    with tgsis.in_version(conn, version), conn.cursor(binary=True) as cursor:
        for t in [r[0] for r in cursor.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))]:
            rows = cursor.execute(
                "SELECT vrtxid, x, y, z FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s ORDER BY vrtxid",
                (geoid, t),
            ).fetchall()
            cells = cursor.execute(
                "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.times_trgl WHERE geoid = %s AND times = %s",
                (geoid, t),
            ).fetchall()
            porosity = cursor.execute(
                sql.SQL("SELECT _idx, porosity FROM {} WHERE _geoid = %s AND _times = %s ORDER BY _idx").format(
                    fc.qualified(vertex_table)
                ),
                (geoid, t),
            ).fetchall()
            throw = cursor.execute(
                sql.SQL("SELECT throw FROM {} WHERE _geoid = %s AND _times = %s").format(fc.qualified(fc.protable)),
                (geoid, t),
            ).fetchall()
            out[repr(float(t))] = (
                [int(r[0]) for r in rows],
                np.array([r[1:] for r in rows], dtype=np.float64).tobytes(),
                sorted(tuple(int(v) for v in c) for c in cells),
                [int(r[0]) for r in porosity],
                np.array([r[1] for r in porosity], dtype=np.float64).tobytes(),
                [float(r[0]) for r in throw],
            )
    conn.commit()
    return out


def _expected(
    edits: dict[float, list[tuple[Any, tuple[float, float, float]]]], times: tuple[float, ...] = TIMES
) -> dict[str, Any]:
    _, cells = _grid(0)
    out = {}
    for i, t in enumerate(times):
        vertices = _grid(i)[0]
        for ids, shift in edits.get(t, []):
            vertices = _shifted(vertices, ids, shift)
        out[repr(t)] = (
            list(range(SIDE * SIDE)),
            vertices.tobytes(),
            sorted((j, *map(int, c)) for j, c in enumerate(cells)),
            list(range(SIDE * SIDE)),
            _porosity(i).tobytes(),
            [10.0 * (i + 1)],
        )
    return out


def _per_instant() -> int:
    """Rows of one instant in the tables a state is read from: its times row, vertices, triangles, property rows."""
    return 1 + SIDE * SIDE + 2 * (SIDE - 1) ** 2 + SIDE * SIDE


def _bound(conn: Conn, rings: int, instants: int) -> int:
    """The rows a merge touching ``instants`` instants may decode: ``rings`` on rows (the change's one-rings).

    In chunks the change read is every slot of a changed chunk (docs/storage.md, "Snapshots at t"): an instant
    here is one chunk per table, so each touched instant is read whole in each of the three states (base,
    parent, child) at most (1,650 and 1,025 rows read here, PG15); an untouched instant read in all three
    exceeds it. The storage is the database's (``tgsis.stored_in_chunks``), not the harness's.
    """
    chunked = conn.execute("SELECT tgsis.stored_in_chunks('times_vrtx')").fetchone() == (True,)
    conn.commit()
    return 3 * instants * _per_instant() if chunked else rings


def _ring(moved: int) -> int:
    """Rows read for an edit moving two whole grid rows (``moved`` vertices) of one instant.

    The rows the sides wrote or closed (the old and new version of each moved
    vertex), the triangles on the moved vertices (two strips: read to find the
    ring, then read again with the rest), the vertices of three grid rows
    (and the old versions of the moved ones) and their property rows. Model
    1's ``read_merge_change`` reads alike; the whole instant is ``_per_instant``.
    """
    strips = 2 * 2 * (SIDE - 1)
    return 2 * moved + 2 * strips + (3 * SIDE + moved) + 3 * SIDE


def test_edits_at_two_instants_read_those_two_only(conn: Conn, series: int, monkeypatch: pytest.MonkeyPatch) -> None:
    _move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    _move(conn, "DEFAULT", series, 6.0, SOUTH, PARENT_SHIFT)
    counted = _rows_decoded(monkeypatch)
    result = tgsis.merge_version(conn, "e1")
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(series), "automatic")]
    # the change and its one-ring at the two touched instants, and their times rows; the two whole instants
    # would be 2 * _per_instant() (and the whole object 8 instants' rows)
    assert counted[0] <= _bound(conn, _ring(len(NORTH)) + _ring(len(SOUTH)) + 2, 2), (counted[0], 2 * _per_instant())
    expected = _expected({2.0: [(NORTH, CHILD_SHIFT)], 6.0: [(SOUTH, PARENT_SHIFT)]})
    for version in ("DEFAULT", "e1"):
        assert _state(conn, version, series) == expected, version
    assert tgsis.find_conflicts(conn, "e1") == []


def test_disjoint_edits_of_one_instant_read_that_instant_only(
    conn: Conn, series: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    _move(conn, "e1", series, 5.0, NORTH, CHILD_SHIFT)
    _move(conn, "DEFAULT", series, 5.0, SOUTH, PARENT_SHIFT)
    counted = _rows_decoded(monkeypatch)
    tgsis.merge_version(conn, "e1")
    assert counted[0] <= _bound(conn, _ring(len(NORTH)) + _ring(len(SOUTH)) + 1, 1), (counted[0], _per_instant())
    expected = _expected({5.0: [(NORTH, CHILD_SHIFT), (SOUTH, PARENT_SHIFT)]})
    for version in ("DEFAULT", "e1"):
        assert _state(conn, version, series) == expected, version


def test_refresh_then_merge_reads_the_change_and_keeps_every_instant(
    conn: Conn, series: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Refresh brings the parent's edit into the version; the merge after writes the version's edit, nothing lost."""
    _move(conn, "e1", series, 1.0, NORTH, CHILD_SHIFT)
    _move(conn, "DEFAULT", series, 8.0, SOUTH, PARENT_SHIFT)
    counted = _rows_decoded(monkeypatch)
    tgsis.refresh_version(conn, "e1")
    assert counted[0] <= _bound(conn, _ring(len(NORTH)) + _ring(len(SOUTH)) + 2, 2), (counted[0], 2 * _per_instant())
    tgsis.merge_version(conn, "e1")
    expected = _expected({1.0: [(NORTH, CHILD_SHIFT)], 8.0: [(SOUTH, PARENT_SHIFT)]})
    for version in ("DEFAULT", "e1"):
        assert _state(conn, version, series) == expected, version


def _statements(conn: Conn, run: Any) -> int:
    """The statements ``run`` sends: libpq's trace of the protocol, a simple Query or an extended query's Bind."""
    with tempfile.TemporaryFile() as trace:
        conn.pgconn.trace(trace.fileno())
        try:
            run()
        finally:
            conn.pgconn.untrace()
        trace.seek(0)
        lines = trace.read().decode("utf-8", "replace").splitlines()
    return sum(1 for line in lines if re.search(r"\tF\t\d+\t(Query|Bind)\b", line))


def test_the_statements_of_a_merge_do_not_grow_with_the_touched_instants(conn: Conn) -> None:
    """The largest ids per touched slice were read by two statements per slice: now one statement for all, as the
    merge's other reads (per table). A merge touching 2 of 20 instants and one touching all 20 send as many
    statements; each writes the union of both sides' edits at every touched instant, bit for bit."""
    times = tuple(float(t) for t in range(1, 21))
    geoid = _series(conn, times)
    counts = []
    edits: dict[float, list[tuple[Any, tuple[float, float, float]]]] = {}
    for touched in (times[:2], times, times[:2]):
        for t in touched:
            _move(conn, "e1", geoid, t, NORTH, CHILD_SHIFT)
            _move(conn, "DEFAULT", geoid, t, SOUTH, PARENT_SHIFT)
            edits.setdefault(t, []).extend([(NORTH, CHILD_SHIFT), (SOUTH, PARENT_SHIFT)])
        counts.append(_statements(conn, lambda: tgsis.merge_version(conn, "e1", remove=True)))
        conn.commit()
        assert _state(conn, "DEFAULT", geoid) == _expected(edits, times)
        tgsis.create_version(conn, "e1")
        conn.commit()
    assert counts[0] == counts[1] == counts[2] and counts[0] > 0, counts
