"""Bytes on disk of a class's vertex property in chunks (issue 40, area K), against the same property as rows.

The 1M-vertex grid of bench/transfer.py (one random double property, ``porosity``: incompressible, the hard
case) uploaded with ``insert_feature`` (vertices and triangles in chunks, model 1's default; the property as
rows), measured, then the class switched by ``tgsis.store_class_in_chunks`` (opt-in) and measured again, after
VACUUM. With ``--versioned``, feature versioning is on before the upload (issue 40 asks the disk figure
versioned): the property rows are measured in their ``_ver`` storage, the chunks in the chunk table that is then
the class's versioned storage (``tgsis.storage_table``); the transfer below is then not run (the bulk paths
serve unversioned classes; a versioned one goes through the face, row by row). Without it, the transfer, in the
same run: ``insert_feature`` and ``fetch_feature`` of the same surface in three classes side by side, in turn
(``--repeat`` times, medians): ``bare`` (no property: the mesh alone), ``onrows`` (the property as rows) and
``inchunks`` (switched while empty: the property's chunks encoded by the client and written by
``tgsis.write_property_chunks``, read back from the chunks); the property's share is each time less the
bare mesh's, and the property's part of the fetch's query is timed alone (``property_read``). ``--face`` also
times the path before the bulk one (the face's rows, its trigger row by row) on a surface of ``--face-side``
(the face's upload takes milliseconds a row). ``--alter`` times instead add_property, rename_property and
drop_property on the class in chunks (in place, ``tgsis.alter_chunk_table``) and, unversioned, the round trip
through rows that an add cost before, in the same run. ``--checkin`` times instead the check-in by
difference (``save_feature`` in version e1 of a versioned class) of a 1 % property edit (every 100th vertex:
scattered, every chunk touched) and of a 100 % one, for classes ``bare`` (no property: the mesh's own
check-in), ``onrows`` and ``inchunks`` (switched after the upload), the property's share less ``bare``'s;
``--shares 1pctlocal`` the first 1 % of the ids (a region in the spatial order);
``inchunksserver`` is a fourth class in chunks whose edit is aggregated by the server
(``tgsis.write_property_rows``, the client's swap switched off: the path of the thirteenth session), against
``inchunks`` (the client encodes the touched chunks, ``tgsis.swap_object_chunks``);
with ``--face`` also the path before (the face's rows, ``tgsis.db._state_write.write_property_rows`` off) against
the bulk one on a surface of ``--face-side``. Prints ``name: value`` lines.

    .venv/bin/python bench/property_chunks.py [--side 1000] [--order spatial|file] [--versioned] [--repeat 3] [--face] [--alter]
    .venv/bin/python bench/property_chunks.py --checkin [--side 1000] [--repeat 1] [--shares 1pct,100pct] [--face] [--face-side 30]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import psycopg
from timing import bench_database
from transfer import grid_surface

import tgsis
import tgsis.db._property_chunks as property_chunks
import tgsis.db._state_write as state_write
import tgsis.db._static as static
from tgsis.db import features as F
from tgsis.db._transfer import Packed, columns_out_all
from tgsis.db.versions import storage_table

Conn = psycopg.Connection[Any]


def total(conn: Conn, relation: str) -> int:
    """pg_total_relation_size of one relation (heap, TOAST, indexes)."""
    row = conn.execute("SELECT pg_total_relation_size(%s::regclass)", (relation,)).fetchone()
    assert row is not None
    return int(row[0])


def seconds(call: Callable[[], Any]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def transfer(
    conn: Conn, surface: Any, order: str, repeat: int, through_face: bool = False, suffix: str = ""
) -> dict[str, float]:
    """Medians of insert_feature + commit and fetch_feature for classes bare, onrows, inchunks, in turn."""
    props = [("porosity", "double precision")]
    classes = {f"bare{suffix}": [], f"onrows{suffix}": props, f"inchunks{suffix}": props}
    bare = tgsis.Surface(surface.vertices, surface.cells)
    for name, props in classes.items():
        tgsis.create_feature_class(conn, name, "SURFACE", cell_properties=props)
    conn.execute("SELECT tgsis.store_class_in_chunks(%s)", (f"inchunks{suffix}",))
    conn.commit()
    saved = static.property_chunks, static.property_request
    if through_face:  # the path before the bulk one: the face's rows, through its trigger
        static.property_chunks = lambda *a: None  # type: ignore[assignment]
        static.property_request = lambda *a: None  # type: ignore[assignment]
    times: dict[str, list[float]] = {}
    try:
        for _ in range(repeat):
            for name in classes:
                mesh = bare if name.startswith("bare") else surface
                geoid = 0

                def upload(name: str = name, mesh: Any = mesh) -> None:
                    nonlocal geoid
                    geoid = F.insert_feature(conn, name, mesh, order=order)
                    conn.commit()

                key = name.removesuffix(suffix)
                times.setdefault(f"{key}_upload", []).append(seconds(upload))
                times.setdefault(f"{key}_fetch", []).append(seconds(lambda: F.fetch_feature(conn, name, geoid)))
                if not key.startswith("bare"):  # the property's part of the fetch's one query, alone
                    fc = tgsis.get_feature_class(conn, name)
                    part = static.property_request(conn, fc, fc.cellprotable, ["porosity"], [geoid]) or Packed(
                        fc.qualified(fc.cellprotable), "_geoid", [("_idx", "int8"), ("porosity", "float8")], [geoid]
                    )
                    times.setdefault(f"{key}_read", []).append(seconds(lambda: columns_out_all(conn, [part])))
                conn.rollback()
    finally:
        static.property_chunks, static.property_request = saved
    if not through_face:  # (a session that wrote through the face holds tables of its row type until it ends)
        for name in classes:
            tgsis.drop_feature_class(conn, name, force=True)
        conn.commit()
    return {k: statistics.median(v) for k, v in times.items()}


def alter(conn: Conn, round_trip: bool) -> None:
    """Time add/rename/drop of a property in place on the class in chunks; the round trip's add too when unversioned.

    The round trip is what ``tgsis.alter_class_table`` did before the change in place (and cannot do for a
    versioned class): ``store_class_in_rows``, the ALTER on rows, ``store_class_in_chunks``, each verified.
    """
    timed = {}
    for name, call in (
        ("add", lambda: tgsis.add_property(conn, "horizon", ("grade", "integer"), default="1")),
        ("rename", lambda: tgsis.rename_property(conn, "horizon", "grade", "grade2")),
        ("drop", lambda: tgsis.drop_property(conn, "horizon", "grade2", force=True)),
    ):
        timed[name] = seconds(lambda call=call: (call(), conn.commit()))
        print(f"in_place_{name}_s: {timed[name]:.2f}")
    if round_trip:

        def trip() -> None:
            conn.execute("SELECT tgsis.store_class_in_rows('horizon')")
            tgsis.add_property(conn, "horizon", ("grade", "integer"), default="1")
            conn.execute("SELECT tgsis.store_class_in_chunks('horizon')")
            conn.commit()

        trip_s = seconds(trip)
        print(f"round_trip_add_s: {trip_s:.2f}")
        print(f"in_place_add_to_round_trip: {timed['add'] / trip_s:.3f}")


#: the property edits of --checkin: the ids changed (of n vertices)
EDITS: dict[str, Callable[[int], slice]] = {
    "1pct": lambda n: slice(None, None, 100),  # every 100th vertex: scattered, every chunk touched
    "1pctlocal": lambda n: slice(0, n // 100),  # the first 1 % of the ids: a region in the spatial order
    "100pct": lambda n: slice(None),
}


def checkins(
    conn: Conn, surface: Any, repeat: int, names: tuple[str, ...], prefix: str = "", shares: tuple[str, ...] = ()
) -> dict[str, float]:
    """Medians of save_feature (in e1, rolled back after each) of the property edits ``shares``, per class."""
    props = [("porosity", "double precision")]
    for name in names:
        tgsis.create_feature_class(conn, f"{prefix}{name}", "SURFACE", cell_properties=[] if name == "bare" else props)
    versioned = conn.execute("SELECT EXISTS (SELECT FROM tgsis.versioned_tables)").fetchone()
    if versioned != (True,):
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    bare = tgsis.Surface(surface.vertices, surface.cells)
    geoids = {n: F.insert_feature(conn, f"{prefix}{n}", bare if n == "bare" else surface) for n in names}
    conn.commit()
    for name in names:
        if name.startswith("inchunks"):
            conn.execute("SELECT tgsis.store_class_in_chunks(%s)", (f"{prefix}{name}",))
    tgsis.create_version(conn, f"{prefix}e1")
    conn.commit()
    times: dict[str, list[float]] = {}
    saved, swapped, edit = state_write.write_property_rows, property_chunks._swapped, state_write.write_property_edit
    spent = [0.0]

    def timed_edit(*args: Any) -> Any:
        """The property table's write alone (write_property_edit), timed: less noisy than the check-in's share."""
        start = time.perf_counter()
        try:
            return edit(*args)
        finally:
            spent[0] += time.perf_counter() - start

    state_write.write_property_edit = timed_edit  # type: ignore[assignment]
    try:
        with tgsis.in_version(conn, f"{prefix}e1"):
            for _ in range(repeat):
                for name in names:  # the check-in reads the stored state: the read's share of it
                    fetched = seconds(lambda n=name: F.fetch_feature(conn, f"{prefix}{n}", geoids[n]))
                    times.setdefault(f"{name}_fetch", []).append(fetched)
                    conn.commit()
                for share in shares or ("1pct", "100pct"):
                    for name in names:
                        stored = F.fetch_feature(conn, f"{prefix}{name}", geoids[name]).mesh
                        conn.commit()
                        assert isinstance(stored, tgsis.Surface)
                        props_now = dict(stored.vertex_properties)
                        if name != "bare":
                            porosity = props_now["porosity"].copy()
                            porosity[EDITS[share](len(porosity))] += 1.0
                            props_now["porosity"] = porosity
                        edited = tgsis.Surface(stored.vertices, stored.cells, vertex_properties=props_now)
                        if name.endswith("face"):  # the path before: the face's rows, its trigger row by row
                            state_write.write_property_rows = lambda *a: None  # type: ignore[assignment]
                        if name.endswith("server"):  # the server's aggregation (tgsis.write_property_rows), no swap
                            property_chunks._swapped = lambda *a: None  # type: ignore[assignment]
                        conn.execute("SELECT 1")  # one transaction, rolled back: each run from the same state
                        spent[0] = 0.0
                        taken = seconds(lambda n=name, e=edited: tgsis.save_feature(conn, f"{prefix}{n}", geoids[n], e))
                        state_write.write_property_rows, property_chunks._swapped = saved, swapped
                        conn.rollback()
                        times.setdefault(f"{name}_{share}", []).append(taken)
                        times.setdefault(f"{name}_{share}_write", []).append(spent[0])
    finally:
        state_write.write_property_rows, property_chunks._swapped = saved, swapped
        state_write.write_property_edit = edit  # type: ignore[assignment]
    return {k: statistics.median(v) for k, v in times.items()}


def report_checkins(
    t: dict[str, float], names: tuple[str, ...], prefix: str, size: int, shares: tuple[str, ...] = ()
) -> None:
    print(f"{prefix}vertices: {size}")
    for name in names:
        print(f"{prefix}fetch_in_version_{name}_s: {t[f'{name}_fetch']:.3f}")
    for share in shares or ("1pct", "100pct"):
        for name in names:
            print(f"{prefix}checkin_{share}_{name}_s: {t[f'{name}_{share}']:.3f}")
        base = t[f"bare_{share}"]
        prop = {n: t[f"{n}_{share}"] - base for n in names if n != "bare"}
        for name, value in prop.items():
            print(f"{prefix}checkin_{share}_property_{name}_s: {value:.3f}")
        write = {n: t[f"{n}_{share}_write"] for n in names if n != "bare"}
        for name, value in write.items():  # the property table's write alone (write_property_edit)
            print(f"{prefix}checkin_{share}_property_write_{name}_s: {value:.3f}")
        for name in write:
            if name != "inchunks" and write[name] > 0:
                print(
                    f"{prefix}checkin_{share}_property_write_inchunks_to_{name}: {write['inchunks'] / write[name]:.3f}"
                )
        for name in prop:
            if name != "inchunks" and prop[name] > 0:
                print(f"{prefix}checkin_{share}_property_inchunks_to_{name}: {prop['inchunks'] / prop[name]:.3f}")
            if name != "inchunks":
                print(
                    f"{prefix}checkin_{share}_inchunks_to_{name}: {t[f'inchunks_{share}'] / t[f'{name}_{share}']:.3f}"
                )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--order", choices=("spatial", "file"), default="spatial")
    parser.add_argument("--versioned", action="store_true", help="feature versioning on before the upload")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--face", action="store_true", help="also the face's row-by-row path, on --face-side")
    parser.add_argument("--face-side", type=int, default=100)
    parser.add_argument(
        "--alter", action="store_true", help="time add/rename/drop property in place (and the round trip) instead"
    )
    parser.add_argument("--checkin", action="store_true", help="time check-ins of property edits instead")
    parser.add_argument("--shares", default="1pct,100pct", help=f"the edits of --checkin, among {sorted(EDITS)}")
    args = parser.parse_args()
    surface = grid_surface(args.side)
    n = surface.n_vertices
    with bench_database() as conn:
        conn.autocommit = False
        if args.checkin:
            names, shares = ("bare", "onrows", "inchunks", "inchunksserver"), tuple(args.shares.split(","))
            report_checkins(checkins(conn, surface, args.repeat, names, "", shares), names, "", n, shares)
            if args.face:
                small = grid_surface(args.face_side)
                names = ("bare", "onrows", "inchunks", "inchunksface")
                t = checkins(conn, small, args.repeat, names, "small")
                report_checkins(t, names, f"side{args.face_side}_", small.n_vertices)
                for share in ("1pct", "100pct"):
                    face = t[f"inchunksface_{share}"] - t[f"bare_{share}"]
                    bulk = t[f"inchunks_{share}"] - t[f"bare_{share}"]
                    if face > 0:
                        print(f"side{args.face_side}_checkin_{share}_property_bulk_to_face: {bulk / face:.4f}")
            return
        tgsis.create_feature_class(conn, "horizon", "SURFACE", cell_properties=[("porosity", "double precision")])
        if args.versioned:
            tgsis.enable_feature_versioning(conn)
        conn.commit()
        print(f"versioned: {int(args.versioned)}")
        start = time.perf_counter()
        geoid = F.insert_feature(conn, "horizon", surface, order=args.order)
        conn.commit()
        print(f"upload_s: {time.perf_counter() - start:.2f}")
        geometry = [storage_table(conn, "tgsis", "vrtx"), storage_table(conn, "tgsis", "trgl")]
        property_rows = storage_table(conn, "public", "horizon_cellpros")  # the table, or its _ver when versioned
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        rows = total(conn, property_rows)
        mesh = sum(total(conn, t) for t in geometry)
        print(f"vertices: {n}")
        print(f"mesh_bytes_per_vertex: {mesh / n:.1f}")
        print(f"property_rows_bytes_per_vertex: {rows / n:.1f}")
        print(f"total_with_property_rows_bytes_per_vertex: {(mesh + rows) / n:.1f}")
        conn.autocommit = False
        start = time.perf_counter()
        conn.execute("SELECT tgsis.store_class_in_chunks('horizon')")
        conn.commit()
        print(f"store_class_in_chunks_s: {time.perf_counter() - start:.2f}")
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        property_chunks = storage_table(conn, "public", "horizon_cellpros")
        assert property_chunks == "public.horizon_cellpros_chunk", property_chunks
        chunks = total(conn, property_chunks)
        print(f"property_chunks_bytes_per_vertex: {chunks / n:.1f}")
        print(f"total_with_property_chunks_bytes_per_vertex: {(mesh + chunks) / n:.1f}")
        start = time.perf_counter()
        fetched = F.fetch_feature(conn, "horizon", geoid).mesh
        print(f"fetch_feature_through_the_face_s: {time.perf_counter() - start:.2f}")
        assert isinstance(fetched, tgsis.Surface) and fetched.n_vertices == n
        conn.autocommit = False
        if args.alter:
            alter(conn, not args.versioned)
        tgsis.drop_feature_class(conn, "horizon", force=True)
        conn.commit()
        if args.versioned or args.alter:
            return
        runs = [("", surface, False)]
        if args.face:
            small = grid_surface(args.face_side)
            runs += [(f"side{args.face_side}_bulk_", small, False), (f"side{args.face_side}_face_", small, True)]
        for prefix, mesh, face in runs:
            t = transfer(conn, mesh, args.order, args.repeat, face, "_face" if face else "")
            for name in ("bare", "onrows", "inchunks"):
                print(f"{prefix}{name}_upload_s: {t[f'{name}_upload']:.3f}")
                print(f"{prefix}{name}_fetch_s: {t[f'{name}_fetch']:.3f}")
            print(f"{prefix}property_read_rows_s: {t['onrows_read']:.3f}")
            print(f"{prefix}property_read_chunks_s: {t['inchunks_read']:.3f}")
            print(f"{prefix}property_read_chunks_to_rows: {t['inchunks_read'] / t['onrows_read']:.2f}")
            for way in ("upload", "fetch"):
                on_rows = t[f"onrows_{way}"] - t[f"bare_{way}"]
                in_chunks = t[f"inchunks_{way}"] - t[f"bare_{way}"]
                print(f"{prefix}property_{way}_rows_s: {on_rows:.3f}")
                print(f"{prefix}property_{way}_chunks_s: {in_chunks:.3f}")
                if on_rows > 0:
                    print(f"{prefix}property_{way}_chunks_to_rows: {in_chunks / on_rows:.2f}")
                print(f"{prefix}{way}_inchunks_to_onrows: {t[f'inchunks_{way}'] / t[f'onrows_{way}']:.2f}")


if __name__ == "__main__":
    main()
