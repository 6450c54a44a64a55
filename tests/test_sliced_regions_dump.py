"""pg_dump / restore of a version with unresolved model-2/3 region conflicts (issue 39, item 5).

Stored regions of a surface at instants and of an evolving surface — their
slice (``times``, ``timem``), ids, solutions, an ``average`` solution's mesh
and the unsolved one — survive a dump and restore (plain and custom); found
again there on the same marks, the solutions still hold; and the merge works
after the restore exactly as it works in the original database (the merged
rows bit for bit).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import psycopg
import pytest

import tgsis
from tests.test_backup import _bindir_of, _restored
from tests.test_conflict_regions import stored
from tests.test_merge_instants import (
    CHILD_SHIFT,
    NORTH,
    PARENT_SHIFT,
    SOUTH,
    geometry_instants,
    instants,
    make_evolving,
    make_series,
    move,
    move3,
)
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]


def _two_conflicts(conn: Conn, model: int) -> int:
    """Conflicts at instants (geometry instants) 1 and 2, a parent-only edit at 3; region of 1 solved average."""
    geoid = make_series(conn) if model == 2 else make_evolving(conn)
    shift = move if model == 2 else move3
    for t in (1.0, 2.0):
        shift(conn, "e1", geoid, t, NORTH, CHILD_SHIFT)
        shift(conn, "DEFAULT", geoid, t, NORTH, PARENT_SHIFT)
    shift(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.region, r.times, r.conflict) for r in conflict.regions] == [
        (0, 1.0, True),
        (1, 2.0, True),
        (2, 3.0, False),
    ]
    tgsis.resolve_region(conn, "e1", geoid, 0, "average")
    conn.commit()
    return geoid


def _finish(conn: Conn, geoid: int) -> None:
    """The rest of the work after the restore: the unsolved region is refused at the merge, then solved, merged."""
    with pytest.raises(tgsis.UnsolvedConflictsError, match="region 1"):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    tgsis.resolve_region(conn, "e1", geoid, 1, "child", discard_other=True)
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()


def _state(model: int) -> Callable[[Conn, str, int], dict[Any, Any]]:
    if model == 2:
        return lambda c, v, g: {
            t: (ids.tobytes(), xyz.tobytes(), cells) for t, (ids, xyz, cells) in instants(c, v, g).items()
        }
    return lambda c, v, g: {k: xyz.tobytes() for k, xyz in geometry_instants(c, v, g).items()}


@pytest.mark.parametrize("model", [2, 3])
def test_unresolved_region_conflicts_of_models_2_and_3_survive_a_dump_and_the_merge_works_after(
    conn: Conn, db_dsn: str, pg: TestServer, tmp_path: Any, model: int
) -> None:
    geoid = _two_conflicts(conn, model)
    before = stored(conn)
    meshes = conn.execute(
        "SELECT region, times, timem, solution, md5(solution_mesh) FROM tgsis.conflict_regions ORDER BY region"
    ).fetchall()
    conn.rollback()
    assert [(r[0], r[1], r[3], r[4] is not None) for r in meshes] == [
        (0, 1.0, "average", True),
        (1, 2.0, "unsolved", False),
        (2, 3.0, "automatic", False),
    ]
    assert all((r[2] == 1.0) if model == 3 else r[2] is None for r in meshes)
    state = _state(model)
    dumps = {}
    for fmt in ("plain", "custom"):
        with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as restored:
            assert stored(restored) == before
            assert (
                restored.execute(
                    "SELECT region, times, timem, solution, md5(solution_mesh) FROM tgsis.conflict_regions"
                    " ORDER BY region"
                ).fetchall()
                == meshes
            )
            restored.rollback()
            [again] = tgsis.find_conflicts(restored, "e1")  # the same marks: the solutions hold
            restored.commit()
            assert [r.solution for r in again.regions] == ["average", "unsolved", "automatic"]
            assert stored(restored) == before
            _finish(restored, geoid)
            dumps[fmt] = (state(restored, "DEFAULT", geoid), state(restored, "e1", geoid))
    unmerged = state(conn, "DEFAULT", geoid)
    _finish(conn, geoid)  # the same work without a dump: the oracle
    expected = (state(conn, "DEFAULT", geoid), state(conn, "e1", geoid))
    assert expected[0] != unmerged and expected[0] == expected[1]  # merged: the version's edits reached DEFAULT
    assert dumps == {"plain": expected, "custom": expected}
