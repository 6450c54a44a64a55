"""What the storage checks cost an editor's upload: a 1M-vertex, 2M-triangle surface into versioned storage.

An editor (a login role of tgsis_editor, not the tables' owner) uploads with
the client's bulk path, binary COPY straight into ``<table>_ver``. Storage
checks such a write twice per statement: the BEFORE statement trigger (write
right, share lock on the version) and the AFTER INSERT statement trigger that
reads the statement's transition table (every row a live row of the working
revision, no object another version locked). Baseline in the same run, in
turn with it: the same upload with the AFTER trigger disabled by the owner,
and the owner's own upload (the triggers' WHEN spares the owner).

    python bench/storage_checks.py [--side 1000] [--repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import uuid

import psycopg
from psycopg.conninfo import conninfo_to_dict, make_conninfo
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis.db import features as F

STORAGE = (
    "tgsis.vrtx_ver",
    "tgsis.trgl_ver",
    "tgsis.geometry_ver",
    "public.horizon_ver",
    "public.horizon_cellpros_ver",
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    surface = grid_surface(args.side)
    rows = 2 * surface.n_vertices + surface.n_cells
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles, 1 vertex property ({rows} rows)")
    editor = f"bench_editor_{uuid.uuid4().hex[:6]}"
    with bench_database() as owner:
        owner.autocommit = True
        owner.execute(f"CREATE ROLE {editor} LOGIN IN ROLE tgsis_editor")
        try:
            F.create_feature_class(owner, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
            tgsis.enable_feature_versioning(owner)
            params = conninfo_to_dict(owner.info.dsn)
            params["user"] = editor
            with psycopg.connect(make_conninfo(**params)) as conn:

                def upload(by: psycopg.Connection[object]) -> None:
                    F.insert_feature(by, "horizon", surface)
                    by.commit()
                    owner.execute("TRUNCATE " + ", ".join(STORAGE))

                def unchecked() -> None:
                    for table in STORAGE:
                        owner.execute(f"ALTER TABLE {table} DISABLE TRIGGER tgsis_storage_rows")
                    try:
                        upload(conn)
                    finally:
                        for table in STORAGE:
                            owner.execute(f"ALTER TABLE {table} ENABLE TRIGGER tgsis_storage_rows")

                checked_s, unchecked_s, owner_s = paired(
                    [lambda: upload(conn), unchecked, lambda: upload(owner)], args.repeat
                )  # type: ignore[arg-type]
        finally:
            owner.execute(f"DROP OWNED BY {editor}")
            owner.execute(f"DROP ROLE {editor}")

    print(f"editor upload, storage checks on:        {checked_s:6.2f} s  {rows / checked_s:12,.0f} rows/s")
    print(f"editor upload, row check off (baseline): {unchecked_s:6.2f} s")
    print(f"owner upload (checks spared):            {owner_s:6.2f} s")
    print(f"editor_upload_s: {checked_s:.3f}")
    print(f"editor_upload_unchecked_s: {unchecked_s:.3f}")
    print(f"owner_upload_s: {owner_s:.3f}")
    print(f"editor_upload_vs_unchecked: {checked_s / unchecked_s:.3f}")


if __name__ == "__main__":
    main()
