"""The cost of the check of direct chunk inserts (``tgsis.chunk_insert_check``) on a 1M-vertex upload (issue 40).

Roles other than the owners keep INSERT on the chunk tables: the client's
binary COPY of a new object writes chunk versions directly, and the
statement trigger ``tgsis_chunk_insert`` checks them (their encoding, and
open versions of revision 0 while the table is not versioned). Its ``WHEN``
spares the chunk table's and tgsis's owners. Measured on a side x side grid
surface (default 1000: 1M vertices, 2M triangles, one vertex property),
model 1 in chunks, in turn within each repetition (medians of ``--repeat``):

- ``owner``: ``insert_feature`` by tgsis's owner (the bench's superuser):
  the trigger does not fire;
- ``editor``: the same by a login role in ``tgsis_editor``: it fires once
  per COPY into ``tgsis.vrtx_chunk`` and ``tgsis.trgl_chunk``;
- ``editor_unchecked``: the editor again with the two triggers disabled
  (``ALTER TABLE ... DISABLE TRIGGER``, by the owner, enabled again after):
  what the check alone costs the editor, whatever else differs between the
  roles (row-level security of the model tables, the versioned views' class
  filter).

The trigger function's own time is read as well from
``pg_stat_xact_user_functions`` (``track_functions = pl``) inside the
editor's upload transaction. The object is deleted (by the owner, untimed)
and the tables VACUUMed after each upload. ``--versioned`` turns feature
versioning on first (the trigger then checks the encoding only; the
versioned storage's own guard runs for every role).

    python bench/insert_check.py [--side 1000] [--repeat 3] [--versioned]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import psycopg
from psycopg import sql
from psycopg.conninfo import make_conninfo
from transfer import grid_surface

import tgsis
from tgsis.db import features as F
from tgsis.db import versions as V
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]
MODES = ("owner", "editor", "editor_unchecked")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--versioned", action="store_true", help="feature versioning on")
    args = parser.parse_args()

    surface = grid_surface(args.side)
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles, 1 vertex property")
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
            admin.execute("ALTER DATABASE bench SET track_functions = 'pl'")
        owner = psycopg.connect(server.dsn("bench"), autocommit=True)
        tgsis.install(owner, method="sql", storage="chunks")
        F.create_feature_class(owner, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
        if args.versioned:
            tgsis.enable_feature_versioning(owner)
        owner.execute("CREATE ROLE bench_editor LOGIN IN ROLE tgsis_editor")
        chunks = [V.storage_table(owner, "tgsis", t) for t in ("vrtx", "trgl")]
        assert all(c.endswith("_chunk") for c in chunks), chunks
        print("storage:", ", ".join(chunks), "(versioned)" if args.versioned else "(unversioned)")
        editor = psycopg.connect(make_conninfo(server.dsn("bench"), user="bench_editor"))

        def triggers(enabled: bool) -> None:
            for chunk in chunks:
                owner.execute(
                    sql.SQL("ALTER TABLE {} {} TRIGGER tgsis_chunk_insert").format(
                        sql.SQL(chunk), sql.SQL("ENABLE" if enabled else "DISABLE")
                    )
                )

        samples: dict[str, list[float]] = {m: [] for m in MODES}
        check_s: list[float] = []
        check_calls: list[int] = []
        for k in range(args.repeat):
            for mode in MODES:
                conn = owner if mode == "owner" else editor
                triggers(mode != "editor_unchecked")
                owner.execute("VACUUM ANALYZE")
                if conn is editor:
                    editor.execute("SELECT 1")  # the upload's transaction: insert_feature's becomes a savepoint
                start = time.perf_counter()
                fid = F.insert_feature(conn, "horizon", surface)
                if conn is editor:
                    row = editor.execute(
                        "SELECT coalesce(sum(calls), 0), coalesce(sum(total_time), 0) FROM pg_stat_xact_user_functions "
                        "WHERE schemaname = 'tgsis' AND funcname = 'chunk_insert_check'"
                    ).fetchone()
                    editor.commit()
                elapsed = time.perf_counter() - start
                samples[mode].append(elapsed)
                if mode == "editor":
                    assert row is not None
                    check_calls.append(int(row[0]))
                    check_s.append(float(row[1]) / 1000)
                    assert check_calls[-1] == 2, check_calls  # one statement per chunk table: it ran
                print(f"  run {k} {mode:17s} upload {elapsed:.2f} s")
                F.delete_feature(owner, "horizon", fid)
        triggers(True)
        editor.close()
        owner.close()
    finally:
        server.destroy()

    figures = {m: statistics.median(s) for m, s in samples.items()}
    check = statistics.median(check_s)
    print(f"upload_owner_s: {figures['owner']:.3f}")
    print(f"upload_editor_s: {figures['editor']:.3f}")
    print(f"upload_editor_unchecked_s: {figures['editor_unchecked']:.3f}")
    print(f"editor_vs_owner: {figures['editor'] / figures['owner']:.3f}")
    print(f"editor_vs_editor_unchecked: {figures['editor'] / figures['editor_unchecked']:.3f}")
    print(f"insert_check_function_s: {check:.3f}")
    print(f"insert_check_share_of_editor_upload: {check / figures['editor']:.3f}")


if __name__ == "__main__":
    main()
