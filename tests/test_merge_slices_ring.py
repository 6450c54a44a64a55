"""The Python merge of models 2/3 reads each touched slice's change and one-ring: the same result as the whole read.

``tgsis.merge_version`` reads of a touched instant (model 3: topology
period) the rows the sides changed and their one-ring only, as model 1's
``read_merge_change`` (docs/merge.md). Hostile cases where the restriction
could change the result: new vertices added on both sides at one instant (the
child's renumbered past the largest id of the whole instant, which lies
outside the ring), and an evolving surface whose period both sides edit at
different geometry instants. Each is merged with the one-ring read and again
(rolled back) with the touched slices read whole: every row of every instant
alike, bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import _merge_states, merging
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

Conn = psycopg.Connection[Any]

SIDE = 8
FAR = 1000  # the id the base's far corner vertex gets: larger than any new id the sides give


def _grid(i: int) -> tuple[np.ndarray, np.ndarray]:
    x, y = np.meshgrid(np.arange(SIDE, dtype=np.float64), np.arange(SIDE, dtype=np.float64))
    z = np.sin(x / 3.0) * np.cos(y / 5.0) + i / 3.0
    cells = []
    for r in range(SIDE - 1):
        for c in range(SIDE - 1):
            a = r * SIDE + c
            cells += [(a, a + 1, a + SIDE), (a + 1, a + SIDE + 1, a + SIDE)]
    return np.stack([x.ravel() * 1.3, y.ravel() / 3.0, z.ravel()], axis=1), np.asarray(cells, dtype=np.int64)


def _rows(conn: Conn, sql_text: str, geoid: int) -> list[tuple[Any, ...]]:
    with conn.cursor(binary=True) as cursor:
        return [tuple(r) for r in cursor.execute(sql_text, (geoid,)).fetchall()]


def _model2_state(conn: Conn, geoid: int) -> dict[str, Any]:
    out = {}
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            out[version] = (
                [
                    (t, v, np.float64(x).tobytes(), np.float64(y).tobytes(), np.float64(z).tobytes())
                    for t, v, x, y, z in _rows(
                        conn,
                        "SELECT times, vrtxid, x, y, z FROM tgsis.times_vrtx WHERE geoid = %s ORDER BY 1, 2",
                        geoid,
                    )
                ],
                _rows(
                    conn,
                    "SELECT times, trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.times_trgl WHERE geoid = %s ORDER BY 1, 2",
                    geoid,
                ),
            )
    return out


def _model3_state(conn: Conn, geoid: int) -> dict[str, Any]:
    out = {}
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            out[version] = (
                [
                    (m, t, n, np.float64(x).tobytes(), np.float64(y).tobytes(), np.float64(z).tobytes())
                    for m, t, n, x, y, z in _rows(
                        conn,
                        "SELECT timem, timet, nodeid, x, y, z FROM tgsis.d4dvrtx WHERE geoid = %s ORDER BY 1, 2, 3",
                        geoid,
                    )
                ],
                _rows(
                    conn,
                    "SELECT timem, trglid, nodeid1, nodeid2, nodeid3 FROM tgsis.d4dtrgl WHERE geoid = %s ORDER BY 1, 2",
                    geoid,
                ),
            )
    return out


def _merged_both_ways(
    conn: Conn, monkeypatch: pytest.MonkeyPatch, state: Callable[[Conn, int], dict[str, Any]], geoid: int
) -> tuple[dict[str, Any], dict[str, Any], int]:
    """The state after the merge with the one-ring read, and (rolled back first) with the touched slices whole."""
    rows_read: list[int] = []
    # the storage the merge reads (the time table of the state read): in chunks, the change read is every slot of a
    # changed chunk (docs/storage.md, "Snapshots at t"), here the whole instant (one chunk), so no smaller
    table = "times_vrtx" if state is _model2_state else "d4dvrtx"
    chunked = conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() == (True,)
    real = _merge_states.read_sliced_states

    def counted(*args: Any, **kwargs: Any) -> Any:
        inputs = real(*args, **kwargs)
        rows_read.append(sum(s.n_vertices for st in inputs.states.values() for s in st.slices.values()))
        return inputs

    monkeypatch.setattr(merging, "read_sliced_states", counted)
    conn.execute("SELECT 1")  # one transaction: what the merge commits is a savepoint of it, rolled back below
    result = merging.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    ring = state(conn, geoid)
    ring_read = rows_read[-1]
    conn.rollback()

    def whole(*args: Any, **kwargs: Any) -> Any:
        kwargs.pop("ring", None)
        return counted(*args, **kwargs)

    monkeypatch.setattr(merging, "read_sliced_states", whole)
    conn.execute("SELECT 1")
    merging.merge_version(conn, "e1")
    whole_state = state(conn, geoid)
    if chunked:
        assert rows_read[-1] >= ring_read  # never more than the whole read
    else:
        assert rows_read[-1] > ring_read  # the whole read holds more: the one-ring read was restricted
    conn.rollback()
    return ring, whole_state, ring_read


def test_new_vertices_on_both_sides_take_ids_past_the_whole_instant(
    conn: Conn, monkeypatch: pytest.MonkeyPatch
) -> None:
    tgsis.create_feature_class(conn, "horizons", "SURFACE", time_model="INSTANTS")
    tgsis.enable_feature_versioning(conn)
    surfaces = [tgsis.Surface(*_grid(i)) for i in range(3)]
    geoid = tgsis.insert_feature(conn, "horizons", SurfaceSeries(np.asarray([1.0, 2.0, 3.0]), surfaces))
    last = SIDE * SIDE - 1  # the far corner: given id FAR at instant 2, outside both edits' rings
    conn.execute(
        "UPDATE tgsis.times_vrtx SET vrtxid = %s WHERE geoid = %s AND times = 2 AND vrtxid = %s", (FAR, geoid, last)
    )
    for j in (1, 2, 3):
        conn.execute(
            f"UPDATE tgsis.times_trgl SET vrtxid{j} = %s WHERE geoid = %s AND times = 2 AND vrtxid{j} = %s",
            (FAR, geoid, last),
        )
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    n_cells = 2 * (SIDE - 1) ** 2
    for version, corner, xyz in (
        ("e1", (0, 1), (0.5, -0.7, 0.25)),
        ("DEFAULT", (SIDE - 2, SIDE - 1), (8.1, -0.9, -0.5)),
    ):
        with tgsis.in_version(conn, version):
            conn.execute(
                "INSERT INTO tgsis.times_vrtx (geoid, times, vrtxid, x, y, z) VALUES (%s, 2, %s, %s, %s, %s)",
                (geoid, SIDE * SIDE, *xyz),
            )
            conn.execute(
                "INSERT INTO tgsis.times_trgl (geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3)"
                " VALUES (%s, 2, %s, %s, %s, %s)",
                (geoid, n_cells, corner[1], corner[0], SIDE * SIDE),
            )
        conn.commit()
    ring, whole, _ = _merged_both_ways(conn, monkeypatch, _model2_state, geoid)
    assert ring == whole
    ids = [r[1] for r in ring["e1"][0] if r[0] == 2.0]
    assert FAR + 1 in ids and SIDE * SIDE in ids  # the child's new vertex renumbered past the whole instant's ids


def test_evolving_surface_edited_at_two_geometry_instants(conn: Conn, monkeypatch: pytest.MonkeyPatch) -> None:
    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    vertices, cells = _grid(0)
    positions = np.stack([_grid(i)[0] for i in range(3)])
    geoid = tgsis.insert_feature(
        conn, "evolving", EvolvingSurface([TopologyPeriod(np.asarray([1.0, 2.0, 3.0]), cells, positions)])
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    for version, timet, ids, dz in (("e1", 1.0, [0, 1, 2], -0.3), ("DEFAULT", 3.0, [SIDE * SIDE - 1], 0.7)):
        with tgsis.in_version(conn, version):
            conn.execute(
                "UPDATE tgsis.d4dvrtx SET z = z + %s WHERE geoid = %s AND timet = %s AND nodeid = ANY(%s)",
                (dz, geoid, timet, ids),
            )
        conn.commit()
    ring, whole, _ = _merged_both_ways(conn, monkeypatch, _model3_state, geoid)
    assert ring == whole
    moved = {(r[1], r[2]): r for r in ring["e1"][0]}
    assert np.frombuffer(moved[(1.0, 0)][5])[0] == positions[0, 0, 2] - 0.3
    assert np.frombuffer(moved[(3.0, SIDE * SIDE - 1)][5])[0] == positions[2, -1, 2] + 0.7
