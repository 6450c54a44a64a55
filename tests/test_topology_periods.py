"""Appending and removing topology periods of a stored evolving surface (issue 18, part 2).

After each change the stored feature must equal the EvolvingSurface built
with the same periods in memory, at every geometry instant and between them
(SQL snapshots against :meth:`EvolvingSurface.at`); bad changes are refused
and leave the feature as it was.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving
from tgsis.temporal import EvolvingSurface

Conn = psycopg.Connection[Any]


def _same(conn: Conn, fid: int, expected: EvolvingSurface) -> None:
    times = sorted({float(t) for p in expected.periods for t in p.times})
    probes = times + [0.5 * (a + b) for a, b in zip(times, times[1:])]
    for t in probes:
        got, want = tgsis.get_at(conn, fid, t), expected.at(t)
        assert (got is None) == (want is None), t
        if got is not None and want is not None:
            assert np.array_equal(got.vertices, want.vertices) and np.array_equal(got.cells, want.cells), t
    assert [s for s, starts in tgsis.instants(conn, fid) if starts] == [p.start for p in expected.periods]


@pytest.fixture
def stored(conn: Conn) -> tuple[int, EvolvingSurface, EvolvingSurface]:
    """A fault of two periods stored, and a surface whose two later periods can follow it."""
    whole = evolving(np.random.default_rng(5), [-10.0, -6.0, -3.0, -1.0], instants_per_period=3)
    first = EvolvingSurface(whole.periods[:2], name="fault")
    tgsis.create_feature_class(conn, "faults", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    fid = tgsis.insert_feature(conn, "faults", first, drop_extra_properties=True)
    conn.commit()
    return fid, first, whole


def _bare(surface: EvolvingSurface) -> EvolvingSurface:
    """Without properties (the class stores none)."""
    return EvolvingSurface(
        [tgsis.TopologyPeriod(p.times, p.triangles, p.positions) for p in surface.periods],
        alive=surface.alive,
        name=surface.name,
    )


def test_append_then_remove_periods(conn: Conn, stored: tuple[int, EvolvingSurface, EvolvingSurface]) -> None:
    fid, first, whole = stored
    tgsis.append_period(conn, "faults", fid, whole.periods[2], drop_extra_properties=True)
    conn.commit()
    _same(conn, fid, _bare(EvolvingSurface(whole.periods[:3])))
    # the ids go on: nodes and triangles of the new period follow the old ones'
    assert conn.execute("SELECT count(DISTINCT nodeid) FROM tgsis.node WHERE geoid = %s", (fid,)).fetchone() == (
        sum(p.n_nodes for p in whole.periods[:3]),
    )
    assert tgsis.delete_period(conn, fid, -10.0) is True  # the first one
    conn.commit()
    _same(conn, fid, _bare(EvolvingSurface(whole.periods[1:3])))
    assert tgsis.delete_period(conn, fid, -3.0) is True  # the last one
    conn.commit()
    _same(conn, fid, _bare(EvolvingSurface(whole.periods[1:2])))
    assert tgsis.delete_period(conn, fid, -7.0) is False  # no period starts there


def test_bad_changes_are_refused_and_change_nothing(
    conn: Conn, stored: tuple[int, EvolvingSurface, EvolvingSurface]
) -> None:
    fid, first, whole = stored
    with pytest.raises(tgsis.InvalidInputError, match="starts at -1.0, not at its last geometry instant -3.0"):
        tgsis.append_period(conn, "faults", fid, whole.periods[3], drop_extra_properties=True)  # a gap
    tgsis.append_period(conn, "faults", fid, whole.periods[2], drop_extra_properties=True)
    conn.commit()
    with pytest.raises(tgsis.InUseError, match="lies between others"):
        tgsis.delete_period(conn, fid, -6.0)
    conn.rollback()
    _same(conn, fid, _bare(EvolvingSurface(whole.periods[:3])))
    tgsis.delete_period(conn, fid, -3.0)
    tgsis.delete_period(conn, fid, -6.0)
    with pytest.raises(tgsis.InUseError, match="is the only one"):
        tgsis.delete_period(conn, fid, -10.0)
    conn.rollback()
    _same(conn, fid, _bare(EvolvingSurface(whole.periods[:1])))


def test_periods_change_in_a_version_only(conn: Conn, stored: tuple[int, EvolvingSurface, EvolvingSurface]) -> None:
    fid, first, whole = stored
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        tgsis.append_period(conn, "faults", fid, whole.periods[2], drop_extra_properties=True)
        conn.commit()
        _same(conn, fid, _bare(EvolvingSurface(whole.periods[:3])))
    _same(conn, fid, _bare(first))  # DEFAULT still has two periods


def test_two_sessions_appending_at_once_take_turns(
    db_dsn: str, stored: tuple[int, EvolvingSurface, EvolvingSurface]
) -> None:
    """The second append waits for the first, then sees the period it added: a clear refusal, never a raw 23505."""
    import threading

    fid, first, whole = stored
    with psycopg.connect(db_dsn) as a, psycopg.connect(db_dsn) as b:
        a.execute("BEGIN")
        tgsis.append_period(a, "faults", fid, whole.periods[2], drop_extra_properties=True)  # not committed yet
        outcome: list[BaseException] = []

        def second() -> None:
            try:
                tgsis.append_period(b, "faults", fid, whole.periods[2], drop_extra_properties=True)
            except BaseException as exc:  # noqa: BLE001 - reported to the test
                outcome.append(exc)

        worker = threading.Thread(target=second)
        worker.start()
        worker.join(1.0)
        assert worker.is_alive()  # b waits for a's lock on the feature
        a.commit()
        worker.join(30)
        assert len(outcome) == 1 and isinstance(outcome[0], tgsis.InvalidInputError)
        assert "starts at -3.0, not at its last geometry instant -1.0" in str(outcome[0])  # a's period is there
    with psycopg.connect(db_dsn) as check:
        _same(check, fid, _bare(EvolvingSurface(whole.periods[:3])))
