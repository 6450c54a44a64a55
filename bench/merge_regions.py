"""Merges by region read from the database: a 1M-vertex surface with two disjoint 1,000-vertex edits (issue 39's figures).

The surface is the bumpy 1000 x 1000 grid of ``transfer.py`` (1,000,000
vertices, 1,996,002 triangles, one vertex property), uploaded into a
versioned class. Two versions are made from DEFAULT; each moves a 40 x 25
patch (1,000 vertices) near one corner and changes the property of 100 of
them; then DEFAULT moves another patch near the opposite corner. The object
is then changed on both sides, disjointly. Timed in one process, medians of
``--repeat`` runs, every write rolled back after it was timed:

- baseline (a): today's object-level merge of one such edit: the conflict of
  version ``objlevel`` solved ``manual`` (the version's object taken, the parent's edit dropped, as a whole
  object), then ``tgsis.merge_version`` (SQL, through
  ``tgsis.db.versions.merge_version``), and the rows it writes;
- (b) ``tgsis.object_merge`` of version ``regions`` (its three states read
  in one snapshot, ``three_way_merge``), and its read alone
  (``read_merge_states``: the base in full, of each side only the rows its
  revisions wrote or closed) against the three full reads through the views
  it replaced;
- (c) the SQL ``tgsis.find_conflicts`` (which objects changed on both sides;
  when the checkout has SQL region detection, it finds and stores the
  regions of the mesh too, as a psql user gets them): the first call in a
  new session (``sql_find_conflicts_first_s``, medians of ``--repeat`` new
  sessions), repeated in one session (rolled back each time, so the regions
  are found again each time), and once the regions are stored (the call
  then only checks them); ``tgsis.mesh_merge_regions`` alone the same way;
  each as a ratio to the Python detection of (d) in the same run;
- (d) when the checkout has them: the region-aware ``find_conflicts``
  (``tgsis.db.regions``: regions computed and recorded) and the region-aware
  ``merge_version`` (``tgsis.db.merging``) of the two disjoint edits, with
  the rows it writes, each as a ratio to (a).

With ``--model2``: (f) a surface at three instants (the same grid at each,
model 2), the version moving a 1,000-vertex patch at the first instant and
DEFAULT another at the last: the psql ``tgsis.merge_version`` merging it
instant by instant in SQL (``tgsis.merge_instants_by_slice``) and the
Python merge, each as a ratio to the object-level merge of the same edit
(the conflict solved ``manual``), with the rows each writes; the Python merge
also with the touched instants read whole (the read before the change's
one-ring one) as the same run's baseline.

The upload of the surface into versioned storage is timed once, then, with
``--upload-cost``, paired: uploads of the same surface (rolled back) with the
storage's revision indexes (``tgsis.create_revision_indexes``) and with them
dropped, in turn, medians of ``--repeat``: what those indexes cost inserts.
The read of the change and its one-ring (``read_merge_change``, what the
merges by region read) is timed beside the whole read.

With ``--model3``: (g) an evolving surface (model 3: one topology period,
three geometry instants of the same grid), the version moving a patch at the
first geometry instant and DEFAULT another at the last: the psql merge
period by period (``tgsis.merge_periods_by_slice``) and the Python merge
geometry instant by instant, as ratios to the object-level merge, and the
Python merge with the touched period read whole (before).

With ``--cell-brin-cost`` (alone): (h) what the cells' vertex BRIN of models
2 and 3 (``tgsis.times_trgl`` on geoid, times, vrtxid1..3; ``tgsis.d4dtrgl``
on geoid, timem, nodeid1..3) costs uploads: the grid at three instants and as
an evolving surface (one period, three geometry instants) uploaded, rolled
back, with that index and without, in turn, medians of ``--repeat``.

    python bench/merge_regions.py [--side 1000] [--repeat 3] [--upload-cost] [--model2 | --model2-only]
        [--model3 | --model3-only] [--cell-brin-cost]
    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from merge3 import patch
from psycopg import sql
from timing import bench_database, timed
from transfer import grid_surface

import tgsis
from tgsis.db import _merge_states
from tgsis.db import features as F
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]


def move(conn: Conn, version: str, geoid: int, ids: np.ndarray, dz: float, valued: np.ndarray | None = None) -> None:
    """Move vertices ``ids`` by ``dz`` in ``version`` (and set the property of ``valued``), one committed transaction."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)", (dz, geoid, [int(i) for i in ids])
        )
        if valued is not None:
            conn.execute(
                sql.SQL("UPDATE {} SET porosity = 0.5 WHERE _geoid = %s AND _idx = ANY(%s)").format(
                    sql.Identifier(tgsis.get_feature_class(conn, "horizon").property_table("VERTEX") or "")
                ),
                (geoid, [int(i) for i in valued]),
            )


def rolled_back(conn: Conn, action: Callable[[], Any]) -> Callable[[], Any]:
    """``action`` in a transaction rolled back afterwards (a merge's writes undone for the next run)."""

    def run() -> Any:
        conn.rollback()
        conn.execute("SELECT 1")  # a transaction open: what the action commits is a savepoint of it
        try:
            return action()
        finally:
            conn.rollback()

    return run


def in_snapshot(conn: Conn, action: Callable[[], Any]) -> Callable[[], Any]:
    """``action`` in a REPEATABLE READ transaction of its own (as ``object_merge`` reads)."""

    def run() -> Any:
        conn.rollback()
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        try:
            return action()
        finally:
            conn.rollback()

    return run


def in_new_session(
    conn: Conn, query: str, args: tuple[Any, ...], stored_regions: int | None = None
) -> Callable[[], Any]:
    """``query`` as the first statement of a new session to the same database (rolled back; the session closed)."""

    def run() -> Any:
        with psycopg.connect(conn.info.dsn) as other:
            try:
                rows = other.execute(query, args).fetchall()
                if stored_regions is not None:
                    count = other.execute(
                        "SELECT count(*) FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('regions')"
                    ).fetchone()
                    assert count == (stored_regions,), count
                return rows
            finally:
                other.rollback()

    return run


def three_full_reads(conn: Conn, version: str, geoid: int) -> None:
    """The read of before: base, parent and child each in full through the versioned views."""
    _versionid, parent, initrevision, working, parent_working = _merge_states.version_row(conn, version)
    fc = tgsis.get_feature_class(conn, "horizon")
    rows = {
        "base": _merge_states._read_state(conn, fc, geoid, version, initrevision),
        "parent": _merge_states._read_state(conn, fc, geoid, parent, parent_working),
        "child": _merge_states._read_state(conn, fc, geoid, version, working),
    }
    _merge_states._states(fc, geoid, rows)


def figures(conn: Conn, side: int, repeat: int, upload_cost: bool = False) -> dict[str, Any]:
    surface = grid_surface(side)
    F.create_feature_class(conn, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    start = time.perf_counter()
    geoid = F.insert_feature(conn, "horizon", surface)
    conn.commit()
    upload = time.perf_counter() - start
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE")
    conn.autocommit = False
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles, uploaded in {upload:.2f} s")

    parent_patch, child_patch = patch(side, 10, 10), patch(side, side - 60, side - 60)
    for version in ("objlevel", "regions"):
        tgsis.create_version(conn, version)
        conn.commit()
        move(conn, version, geoid, child_patch, -3.0, valued=child_patch[:100])
    move(conn, "DEFAULT", geoid, parent_patch, 5.0)
    print(f"DEFAULT moved {len(parent_patch)} vertices; versions objlevel and regions moved {len(child_patch)} others")

    # (a) the baseline: object-level, the conflict solved 'manual' (the version's object), then the SQL merge
    V.find_conflicts(conn, "objlevel")
    V.resolve_conflict(conn, "objlevel", "feature", geoid, "manual")  # child: refused, it drops an edit
    conn.commit()
    rows_a = int(rolled_back(conn, lambda: V.merge_version(conn, "objlevel"))())
    t_a = timed(rolled_back(conn, lambda: V.merge_version(conn, "objlevel")), repeat)

    # (b) object_merge, and its read against the three full reads it replaced
    merge = tgsis.object_merge(conn, "regions", geoid)
    assert merge.merged is not None and not merge.conflicts and len(merge.regions) == 2, [
        (r.sides, len(r.vertex_ids)) for r in merge.regions
    ]
    expected = surface.vertices.copy()
    expected[parent_patch, 2] += 5.0
    expected[child_patch, 2] -= 3.0
    assert np.array_equal(merge.merged.state.vertices.view(np.int64), expected.view(np.int64))
    conn.rollback()
    t_object_merge = timed(in_snapshot(conn, lambda: tgsis.object_merge(conn, "regions", geoid)), repeat)
    t_read = timed(in_snapshot(conn, lambda: _merge_states.read_merge_states(conn, "regions", geoid)), repeat)
    t_full = timed(in_snapshot(conn, lambda: three_full_reads(conn, "regions", geoid)), repeat)
    t_change = timed(in_snapshot(conn, lambda: _merge_states.read_merge_change(conn, "regions", geoid)), repeat)

    # (c) the SQL conflict check (with the regions found in SQL when the checkout has it), repeated in one session
    t_sql_conflicts = timed(
        rolled_back(conn, lambda: conn.execute("SELECT * FROM tgsis.find_conflicts('regions')").fetchall()), repeat
    )
    out: dict[str, Any] = {
        "upload_s": round(upload, 3),
        "objlevel_merge_s": round(t_a, 3),
        "objlevel_merge_rows": rows_a,
        "object_merge_s": round(t_object_merge, 3),
        "object_merge_vs_objlevel": round(t_object_merge / t_a, 2),
        "read_merge_states_s": round(t_read, 3),
        "three_full_reads_s": round(t_full, 3),
        "read_vs_full": round(t_read / t_full, 2),
        "read_merge_change_s": round(t_change, 3),
        "change_read_vs_full": round(t_change / t_full, 3),
        "sql_find_conflicts_s": round(t_sql_conflicts, 3),
    }
    print(f"(a) baseline, object-level merge of one edit (SQL merge_version): {t_a:6.3f} s, {rows_a} rows written")
    print(
        f"(b) object_merge (read + three_way_merge) of two disjoint edits:  {t_object_merge:6.3f} s ({t_object_merge / t_a:.2f}x (a))"
    )
    print(f"    its read_merge_states:                                        {t_read:6.3f} s")
    print(
        f"    three full reads through the views (the read of before):      {t_full:6.3f} s (the read is {t_read / t_full:.2f}x)"
    )
    print(
        f"    read_merge_change (the change and its one-ring):               {t_change:6.3f} s (the read is {t_change / t_full:.3f}x)"
    )
    print(f"(c) SQL tgsis.find_conflicts, repeated in one session:           {t_sql_conflicts:6.3f} s")
    # (c') issue39-sqlmerge: SQL finds the regions itself (tgsis.mesh_merge_regions, which the SQL find_conflicts
    # of (c) runs for a mesh without regions stored on its marks: (c) includes it when the function exists)
    sql_detection = {}
    if conn.execute("SELECT to_regprocedure('tgsis.mesh_merge_regions(text, bigint)')").fetchone() != (None,):
        in_sql = "SELECT region, conflict, cardinality(vertex_ids) FROM tgsis.mesh_merge_regions('regions', %s)"
        found = rolled_back(conn, lambda: conn.execute(in_sql, (geoid,)).fetchall())()
        assert [r[1:] for r in found] == [(False, len(r.vertex_ids)) for r in merge.regions], found
        t_sql_regions = timed(rolled_back(conn, lambda: conn.execute(in_sql, (geoid,)).fetchall()), repeat)
        conflicts = "SELECT * FROM tgsis.find_conflicts('regions')"
        t_first = timed(in_new_session(conn, conflicts, (), stored_regions=2), repeat)
        t_regions_first = timed(in_new_session(conn, in_sql, (geoid,)), repeat)

        def stored_then_again() -> float:  # the regions found and stored, then the call again: it only checks them
            conn.execute(conflicts).fetchall()
            start = time.perf_counter()
            conn.execute(conflicts).fetchall()
            return time.perf_counter() - start

        t_stored = statistics.median(rolled_back(conn, stored_then_again)() for _ in range(repeat))
        sql_detection = {
            "sql_find_conflicts_first_s": t_first,
            "sql_find_conflicts_s": t_sql_conflicts,
            "sql_region_detection_first_s": t_regions_first,
            "sql_region_detection_s": t_sql_regions,
        }
        out.update(
            {
                "sql_find_conflicts_first_s": round(t_first, 3),
                "sql_find_conflicts_stored_s": round(t_stored, 3),
                "sql_region_detection_first_s": round(t_regions_first, 3),
                "sql_region_detection_s": round(t_sql_regions, 3),
            }
        )
        print(
            f"(c) SQL tgsis.find_conflicts, first call of a new session:       {t_first:6.3f} s (regions found, stored)"
        )
        print(f"(c) SQL tgsis.find_conflicts, the regions stored already:        {t_stored:6.3f} s")
        print(f"(c') SQL region detection alone (tgsis.mesh_merge_regions), first: {t_regions_first:6.3f} s")
        print(f"(c') SQL region detection alone, repeated in one session:        {t_sql_regions:6.3f} s")

    # (d) the region-aware conflict check and merge, when this checkout has them
    if importlib.util.find_spec("tgsis.db.regions") is not None:
        from tgsis.db import regions

        [conflict] = rolled_back(conn, lambda: regions.find_conflicts(conn, "regions"))()
        assert conflict.regions and not any(r.conflict for r in conflict.regions), conflict
        t_regions = timed(rolled_back(conn, lambda: regions.find_conflicts(conn, "regions")), repeat)
        out["region_find_conflicts_s"] = round(t_regions, 3)
        print(f"(d) region-aware find_conflicts (regions found and recorded):     {t_regions:6.3f} s")
        for name, seconds in sql_detection.items():  # SQL detection against Python's, in this run
            out[name.removesuffix("_s") + "_vs_python"] = round(seconds / t_regions, 2)
            print(f"    {name} / (d): {seconds / t_regions:.2f}")
    else:
        print("(d) no tgsis.db.regions in this checkout: region-aware find_conflicts not measured")
    from tgsis.db import merging

    if hasattr(merging, "merge_version"):
        rows_d = int(rolled_back(conn, lambda: merging.merge_version(conn, "regions"))())
        t_d = timed(rolled_back(conn, lambda: merging.merge_version(conn, "regions")), repeat)
        out.update(
            {
                "region_merge_s": round(t_d, 3),
                "region_merge_rows": rows_d,
                "region_merge_vs_objlevel": round(t_d / t_a, 2),
            }
        )
        print(
            f"(d) region-aware merge_version of two disjoint edits:             {t_d:6.3f} s ({t_d / t_a:.2f}x (a)), {rows_d} rows written"
        )
    else:
        print("(d) no region-aware merge_version in this checkout: not measured")
    # (e) issue39-sqlwrite: the psql merge by region (SQL tgsis.merge_version merges the mesh itself, in PL/pgSQL)
    if conn.execute("SELECT to_regprocedure('tgsis.merge_regions_in_sql(text, text, boolean)')").fetchone() != (None,):
        psql_merge = "SELECT tgsis.merge_version('regions')"
        rows_e = int(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()[0])())  # type: ignore[index]
        t_e = timed(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()), repeat)
        out.update(
            {
                "sql_region_merge_s": round(t_e, 3),
                "sql_region_merge_rows": rows_e,
                "sql_region_merge_vs_objlevel": round(t_e / t_a, 2),
            }
        )
        print(
            f"(e) psql merge_version by region (SQL) of two disjoint edits:    {t_e:6.3f} s ({t_e / t_a:.2f}x (a)), {rows_e} rows written"
        )
    if upload_cost:
        out.update(upload_with_and_without_indexes(conn, surface, repeat))
    return out


def move_at(conn: Conn, version: str, geoid: int, t: float, ids: np.ndarray, dz: float) -> None:
    """Move vertices ``ids`` of a surface at instants at instant ``t`` by ``dz`` (one committed UPDATE, as in psql)."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.times_vrtx SET z = z + %s WHERE geoid = %s AND times = %s AND vrtxid = ANY(%s)",
            (dz, geoid, t, ids.tolist()),
        )
    conn.commit()


def whole_slices(action: Callable[[], Any]) -> Callable[[], Any]:
    """``action`` with the Python merge reading the touched slices whole (the read before the one-ring one): the
    baseline of the same run."""
    from tgsis.db import merging

    def run() -> Any:
        real = merging.read_sliced_states

        def whole(*args: Any, **kwargs: Any) -> Any:
            kwargs.pop("ring", None)
            return real(*args, **kwargs)

        merging.read_sliced_states = whole  # type: ignore[assignment]
        try:
            return action()
        finally:
            merging.read_sliced_states = real  # type: ignore[assignment]

    return run


def model2_figures(conn: Conn, side: int, repeat: int) -> dict[str, Any]:
    """(f) the merge of a surface at three instants, edits at different instants, psql and Python against (a)'s kind."""
    from tgsis.db import merging
    from tgsis.temporal import SurfaceSeries

    surface = grid_surface(side)
    F.create_feature_class(conn, "horizons2", "SURFACE", time_model="INSTANTS")
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    series = SurfaceSeries(np.asarray([1.0, 2.0, 3.0]), [tgsis.Surface(surface.vertices, surface.cells)] * 3)
    start = time.perf_counter()
    geoid = F.insert_feature(conn, "horizons2", series)
    conn.commit()
    upload = time.perf_counter() - start
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE")
    conn.autocommit = False
    print(f"(f) surface at 3 instants: {3 * surface.n_vertices} vertex rows, uploaded in {upload:.2f} s", flush=True)
    parent_patch, child_patch = patch(side, 10, 10), patch(side, side - 60, side - 60)
    for version in ("objlevel2", "slices"):
        tgsis.create_version(conn, version)
        conn.commit()
        move_at(conn, version, geoid, 1.0, child_patch, -3.0)
    move_at(conn, "DEFAULT", geoid, 3.0, parent_patch, 5.0)
    V.find_conflicts(conn, "objlevel2")
    V.resolve_conflict(conn, "objlevel2", "feature", geoid, "manual")
    conn.commit()
    rows_a = int(rolled_back(conn, lambda: V.merge_version(conn, "objlevel2"))())
    t_a = timed(rolled_back(conn, lambda: V.merge_version(conn, "objlevel2")), repeat)
    psql_merge = "SELECT tgsis.merge_version('slices')"
    print(f"(f) object-level merge of the version's edit (solved manual):      {t_a:6.3f} s, {rows_a} rows written")
    rows_sql = int(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()[0])())  # type: ignore[index]
    t_sql = timed(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()), repeat)
    print(
        f"(f) psql merge_version instant by instant (SQL):                  {t_sql:6.3f} s ({t_sql / t_a:.2f}x), {rows_sql} rows written",
        flush=True,
    )
    rows_whole = int(whole_slices(rolled_back(conn, lambda: merging.merge_version(conn, "slices")))())
    t_whole = timed(whole_slices(rolled_back(conn, lambda: merging.merge_version(conn, "slices"))), repeat)
    print(
        f"(f) Python merge_version, touched instants read whole (before):  {t_whole:6.3f} s ({t_whole / t_a:.2f}x), {rows_whole} rows written",
        flush=True,
    )
    rows_py = int(rolled_back(conn, lambda: merging.merge_version(conn, "slices"))())
    t_py = timed(rolled_back(conn, lambda: merging.merge_version(conn, "slices")), repeat)
    print(
        f"(f) Python merge_version instant by instant (change + one-ring): {t_py:6.3f} s ({t_py / t_a:.2f}x), {rows_py} rows written"
    )
    return {
        "model2_upload_s": round(upload, 3),
        "model2_objlevel_merge_s": round(t_a, 3),
        "model2_objlevel_merge_rows": rows_a,
        "model2_sql_merge_s": round(t_sql, 3),
        "model2_sql_merge_rows": rows_sql,
        "model2_sql_merge_vs_objlevel": round(t_sql / t_a, 2),
        "model2_python_merge_s": round(t_py, 3),
        "model2_python_merge_rows": rows_py,
        "model2_python_merge_whole_slices_s": round(t_whole, 3),
        "model2_python_merge_whole_slices_rows": rows_whole,
        "model2_python_vs_whole_slices": round(t_py / t_whole, 2),
        "model2_python_vs_sql": round(t_py / t_sql, 2),
        "model2_sql_vs_python": round(t_sql / t_py, 2),
    }


def move_at3(conn: Conn, version: str, geoid: int, timet: float, ids: np.ndarray, dz: float) -> None:
    """Move nodes ``ids`` of an evolving surface at geometry instant ``timet`` by ``dz`` (one committed UPDATE)."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET z = z + %s WHERE geoid = %s AND timet = %s AND nodeid = ANY(%s)",
            (dz, geoid, timet, ids.tolist()),
        )
    conn.commit()


def model3_figures(conn: Conn, side: int, repeat: int) -> dict[str, Any]:
    """(g) the merge of an evolving surface (one topology period, three geometry instants), edits at different
    instants: the psql merge (period by period) and the Python merge against the object-level merge."""
    from tgsis.db import merging
    from tgsis.temporal import EvolvingSurface, TopologyPeriod

    surface = grid_surface(side)
    F.create_feature_class(conn, "evolving3", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    positions = np.stack([surface.vertices] * 3)
    period = TopologyPeriod(np.asarray([1.0, 2.0, 3.0]), surface.cells, positions)
    start = time.perf_counter()
    geoid = F.insert_feature(conn, "evolving3", EvolvingSurface([period]))
    conn.commit()
    upload = time.perf_counter() - start
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE")
    conn.autocommit = False
    print(
        f"(g) evolving surface, 3 geometry instants: {3 * surface.n_vertices} node positions, uploaded in {upload:.2f} s"
    )
    parent_patch, child_patch = patch(side, 10, 10), patch(side, side - 60, side - 60)
    for version in ("objlevel3", "slices3"):
        tgsis.create_version(conn, version)
        conn.commit()
        move_at3(conn, version, geoid, 1.0, child_patch, -3.0)
    move_at3(conn, "DEFAULT", geoid, 3.0, parent_patch, 5.0)
    V.find_conflicts(conn, "objlevel3")
    V.resolve_conflict(conn, "objlevel3", "feature", geoid, "manual")
    conn.commit()
    rows_a = int(rolled_back(conn, lambda: V.merge_version(conn, "objlevel3"))())
    t_a = timed(rolled_back(conn, lambda: V.merge_version(conn, "objlevel3")), repeat)
    print(f"(g) object-level merge of the version's edit (solved manual):      {t_a:6.3f} s, {rows_a} rows written")
    psql_merge = "SELECT tgsis.merge_version('slices3')"
    rows_sql = int(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()[0])())  # type: ignore[index]
    t_sql = timed(rolled_back(conn, lambda: conn.execute(psql_merge).fetchone()), repeat)
    print(
        f"(g) psql merge_version period by period (SQL):                   {t_sql:6.3f} s ({t_sql / t_a:.2f}x), {rows_sql} rows written",
        flush=True,
    )
    rows_whole = int(whole_slices(rolled_back(conn, lambda: merging.merge_version(conn, "slices3")))())
    t_whole = timed(whole_slices(rolled_back(conn, lambda: merging.merge_version(conn, "slices3"))), repeat)
    print(
        f"(g) Python merge_version, touched period read whole (before):    {t_whole:6.3f} s ({t_whole / t_a:.2f}x), {rows_whole} rows written",
        flush=True,
    )
    rows_py = int(rolled_back(conn, lambda: merging.merge_version(conn, "slices3"))())
    t_py = timed(rolled_back(conn, lambda: merging.merge_version(conn, "slices3")), repeat)
    print(
        f"(g) Python merge_version geometry instant by instant (one-ring): {t_py:6.3f} s ({t_py / t_a:.2f}x), {rows_py} rows written"
    )
    return {
        "model3_upload_s": round(upload, 3),
        "model3_objlevel_merge_s": round(t_a, 3),
        "model3_objlevel_merge_rows": rows_a,
        "model3_python_merge_s": round(t_py, 3),
        "model3_python_merge_rows": rows_py,
        "model3_python_merge_whole_slices_s": round(t_whole, 3),
        "model3_python_merge_whole_slices_rows": rows_whole,
        "model3_python_vs_whole_slices": round(t_py / t_whole, 2),
        "model3_python_vs_objlevel": round(t_py / t_a, 2),
        "model3_sql_merge_s": round(t_sql, 3),
        "model3_sql_merge_rows": rows_sql,
        "model3_python_vs_sql": round(t_py / t_sql, 2),
    }


def _revision_indexes(conn: Conn) -> list[tuple[str, str]]:
    """(index, definition) of the revision indexes of the class's storage (BRINs on revision and on the cells'
    vertex columns, btree WHERE revclosed)."""
    rows = conn.execute(
        "SELECT i.indexrelid::regclass::text, pg_get_indexdef(i.indexrelid) FROM pg_index i"
        " JOIN pg_class c ON c.oid = i.indexrelid JOIN pg_am a ON a.oid = c.relam"
        " WHERE i.indrelid::regclass::text IN (SELECT tgsis.storage_table(schemaname, tablename)"
        "        FROM tgsis.versioned_tables WHERE objectclass = 'feature')"
        "   AND ((a.amname = 'brin' AND (pg_get_indexdef(i.indexrelid) LIKE '%(revision)%'"
        "                              OR pg_get_indexdef(i.indexrelid) LIKE '%(geoid, vrtxid1, vrtxid2, vrtxid3)%'))"
        "        OR pg_get_expr(i.indpred, i.indrelid) = 'revclosed')"
    ).fetchall()
    conn.commit()
    return [(str(r[0]), str(r[1])) for r in rows]


def upload_with_and_without_indexes(conn: Conn, surface: Any, repeat: int) -> dict[str, Any]:
    """Uploads of the surface (rolled back) with the revision indexes and without, in turn: medians and their ratio."""
    indexes = _revision_indexes(conn)
    assert indexes, "no revision indexes in this checkout"
    with_s, without_s = paired_uploads(conn, lambda: F.insert_feature(conn, "horizon", surface), indexes, repeat)
    print(
        f"upload with the revision indexes: {with_s:.2f} s, without: {without_s:.2f} s "
        f"({with_s / without_s:.3f}x; {len(indexes)} indexes)"
    )
    return {
        "upload_with_indexes_s": round(with_s, 3),
        "upload_without_indexes_s": round(without_s, 3),
        "upload_indexes_ratio": round(with_s / without_s, 3),
    }


def paired_uploads(
    conn: Conn, upload: Callable[[], Any], indexes: list[tuple[str, str]], repeat: int
) -> tuple[float, float]:
    """Medians of ``upload`` (rolled back) with ``indexes`` (name, definition) and with them dropped, in turn."""

    def once() -> float:
        start = time.perf_counter()
        upload()
        elapsed = time.perf_counter() - start
        conn.rollback()
        return elapsed

    samples: dict[bool, list[float]] = {True: [], False: []}
    for i in range(repeat):  # in turn, the order swapped each time, so that drift of the machine hits both alike
        for indexed in (True, False) if i % 2 == 0 else (False, True):
            if indexed:
                samples[True].append(once())
                continue
            for name, _definition in indexes:
                conn.execute(sql.SQL("DROP INDEX {}").format(sql.SQL(name)))
            conn.commit()
            try:
                samples[False].append(once())
            finally:
                for _name, definition in indexes:
                    conn.execute(definition)
                conn.commit()
    print(f"  samples with: {[round(x, 2) for x in samples[True]]}, without: {[round(x, 2) for x in samples[False]]}")
    return statistics.median(samples[True]), statistics.median(samples[False])


def cell_brin_upload_cost(conn: Conn, side: int, repeat: int) -> dict[str, Any]:
    """(h) what the cells' vertex BRIN of models 2 and 3 (tgsis.times_trgl on geoid, times, vrtxid1..3;
    tgsis.d4dtrgl on geoid, timem, nodeid1..3) costs uploads: a surface at three instants and an evolving surface
    (one period, three geometry instants) of the grid uploaded (rolled back) with that index and without, in turn."""
    from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

    surface = grid_surface(side)
    F.create_feature_class(conn, "upload2", "SURFACE", time_model="INSTANTS")
    F.create_feature_class(conn, "upload3", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    out: dict[str, Any] = {}
    series = SurfaceSeries(np.asarray([1.0, 2.0, 3.0]), [tgsis.Surface(surface.vertices, surface.cells)] * 3)
    positions = np.stack([surface.vertices] * 3)
    evolving = EvolvingSurface([TopologyPeriod(np.asarray([1.0, 2.0, 3.0]), surface.cells, positions)])
    for model, table, upload in (
        ("model2", "times_trgl", lambda: F.insert_feature(conn, "upload2", series)),
        ("model3", "d4dtrgl", lambda: F.insert_feature(conn, "upload3", evolving)),
    ):
        indexes = [
            (str(r[0]), str(r[1]))
            for r in conn.execute(
                "SELECT i.indexrelid::regclass::text, pg_get_indexdef(i.indexrelid) FROM pg_index i"
                " JOIN pg_class c ON c.oid = i.indexrelid JOIN pg_am a ON a.oid = c.relam"
                " WHERE i.indrelid = %s::regclass AND a.amname = 'brin'"
                "   AND pg_get_indexdef(i.indexrelid) ~ '(vrtxid|nodeid)1'",
                (f"tgsis.{table}_ver",),
            ).fetchall()
        ]
        conn.commit()
        assert indexes, f"no vertex BRIN on tgsis.{table}_ver in this checkout"
        with_s, without_s = paired_uploads(conn, upload, indexes, repeat)
        print(
            f"(h) {model} upload with the vertex BRIN of tgsis.{table}: {with_s:.2f} s, without: {without_s:.2f} s "
            f"({with_s / without_s:.3f}x)",
            flush=True,
        )
        out[f"{model}_upload_with_cell_brin_s"] = round(with_s, 3)
        out[f"{model}_upload_without_cell_brin_s"] = round(without_s, 3)
        out[f"{model}_upload_cell_brin_ratio"] = round(with_s / without_s, 3)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--upload-cost", action="store_true", help="time uploads with and without the revision indexes")
    parser.add_argument("--model2", action="store_true", help="(f) also the merge of a surface at three instants")
    parser.add_argument("--model2-only", action="store_true", help="(f) only")
    parser.add_argument("--model3", action="store_true", help="(g) also the merge of an evolving surface")
    parser.add_argument("--model3-only", action="store_true", help="(g) only")
    parser.add_argument(
        "--cell-brin-cost",
        action="store_true",
        help="(h) only: uploads of models 2 and 3 with and without the cells' vertex BRIN",
    )
    args = parser.parse_args()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}, "
        f"{platform.python_implementation()} {platform.python_version()}, numpy {np.__version__}; medians of {args.repeat}"
    )
    with bench_database() as conn:
        if args.cell_brin_cost:
            for name, value in cell_brin_upload_cost(conn, args.side, args.repeat).items():
                print(f"{name}: {value}")
            return
        only = args.model2_only or args.model3_only
        results = {} if only else figures(conn, args.side, args.repeat, args.upload_cost)
        if args.model2 or args.model2_only:
            results.update(model2_figures(conn, args.side, args.repeat))
        if args.model3 or args.model3_only:
            results.update(model3_figures(conn, args.side, args.repeat))
    for name, value in results.items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
