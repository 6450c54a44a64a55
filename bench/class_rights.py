"""What per-class rights at the model tables cost an editor (issue 36, point 8).

Feature versioning on; an editor (a login role in tgsis_editor) who may not
read one class ("secret", one feature), so that the policies' set of denied
geoids is not empty. Measured as that editor: the upload of a side x side
surface (insert_feature: binary COPY, which under row-level security goes
through a temporary table), its download (fetch_feature, through the
versioned views) and a box query over 300 small features (features_in_box,
GiST on tgsis.geometry, plus a vertex-window count on tgsis.vrtx).
Baseline in the same process, same database: the model tables' row-level
security disabled and their versioned views made again without the class
filter (what main had), the operations run in turn with and without.

    python bench/class_rights.py [--side 1000] [--repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
import psycopg
from psycopg.conninfo import make_conninfo
from timing import timed
from transfer import grid_surface

import tgsis
from tests.synthetic import flat_grid
from tgsis.db import features as F
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]


def _views(su: Conn, filtered: bool) -> None:
    """The model tables with (as installed) or without (main's) per-class rights."""
    rows = su.execute(
        "SELECT t.tablename, t.geoidcolumn, ARRAY(SELECT a.attname::text FROM pg_attribute a "
        "  WHERE a.attrelid = format('tgsis.%I', t.tablename || '_ver')::regclass AND a.attnum > 0 AND NOT a.attisdropped"
        "    AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed') ORDER BY a.attnum) "
        "FROM tgsis.model_tables t JOIN tgsis.versioned_tables v ON v.schemaname = 'tgsis' AND v.tablename = t.tablename "
        "WHERE t.geoidcolumn IS NOT NULL"
    ).fetchall()
    for table, geoid, columns in rows:
        source = su.execute("SELECT tgsis.versioned_view_source('tgsis', %s, %s)", (table, columns)).fetchone()
        assert source is not None
        text = source[0].replace("CREATE VIEW", "CREATE OR REPLACE VIEW", 1)
        if filtered:
            text += f" AND v.{geoid} NOT IN (SELECT tgsis.class_denied_geoids('SELECT'))"
        su.execute(text)
        su.execute(f"ALTER VIEW tgsis.{table} SET (security_barrier = {'true' if filtered else 'false'})")
        su.execute(f"ALTER TABLE tgsis.{table}_ver {'ENABLE' if filtered else 'DISABLE'} ROW LEVEL SECURITY")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    surface = grid_surface(args.side)
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles, 1 vertex property")
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        admin = psycopg.connect(server.dsn(), autocommit=True)
        admin.execute("CREATE DATABASE bench")
        su = psycopg.connect(server.dsn("bench"), autocommit=True)
        tgsis.install(su, method="sql")
        F.create_feature_class(su, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
        F.create_feature_class(su, "small", "SURFACE")
        F.create_feature_class(su, "secret", "SURFACE")
        tgsis.enable_feature_versioning(su)
        F.insert_feature(su, "secret", flat_grid(10, 0.0))
        for i in range(300):
            F.insert_feature(su, "small", flat_grid(4, float(i)))
        su.execute("REVOKE ALL ON secret, secret_cellpros FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
        su.execute("CREATE ROLE bench_editor LOGIN IN ROLE tgsis_editor")
        su.execute("VACUUM ANALYZE")
        editor = psycopg.connect(make_conninfo(server.dsn("bench"), user="bench_editor"))
        stored: list[int] = []

        def upload() -> None:
            stored.append(F.insert_feature(editor, "horizon", surface))
            editor.commit()

        def download() -> None:
            F.fetch_feature(editor, "horizon", stored[-1])
            editor.commit()

        def box() -> None:
            for i in range(20):
                F.features_in_box(editor, "small", [[0, 0, i], [2, 2, i + 5]])
                editor.execute(
                    "SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND x < 100 AND y < 100", (stored[-1],)
                ).fetchone()
            editor.commit()

        def drop() -> None:
            F.delete_feature(editor, "horizon", stored.pop())
            editor.commit()

        figures: dict[str, dict[str, float]] = {}
        for mode in ("baseline", "policies", "baseline", "policies"):
            _views(su, mode == "policies")
            su.execute("VACUUM ANALYZE")
            up = timed(upload, 1, None)
            down = timed(download, args.repeat)
            query = timed(box, args.repeat)
            drop()
            previous = figures.get(mode)
            now = {"upload": up, "download": down, "box": query}
            figures[mode] = {k: min(v, previous[k]) for k, v in now.items()} if previous else now
            print(f"{mode}: upload {up:.3f} s, download {down:.3f} s, 20 box queries {query:.3f} s")
        base, rls = figures["baseline"], figures["policies"]
        print(f"upload_baseline_s: {base['upload']:.3f}")
        print(f"upload_policies_s: {rls['upload']:.3f}")
        print(f"upload_ratio: {rls['upload'] / base['upload']:.2f}")
        print(f"download_baseline_s: {base['download']:.3f}")
        print(f"download_policies_s: {rls['download']:.3f}")
        print(f"download_ratio: {rls['download'] / base['download']:.2f}")
        print(f"box_baseline_s: {base['box']:.4f}")
        print(f"box_policies_s: {rls['box']:.4f}")
        print(f"box_ratio: {rls['box'] / base['box']:.2f}")
        print(f"vertices: {np.int64(surface.n_vertices)}")
    finally:
        server.destroy()


if __name__ == "__main__":
    main()
