"""Mesh comparison in SQL (tgsis.compare_geometries & co.) on a 1M-vertex surface, vs the Python comparison.

A bumpy 1000 x 1000 grid (1M vertices, 1,996,002 triangles) is stored, then
an edited copy: vertex and triangle order shuffled, 1 % of the vertices
moved, 0.1 % of the triangles reversed. Timed:

- ``tgsis.compare_geometries`` (six summary rows, ids of removed/added rows),
- ``tgsis.geometry_changes`` read by binary COPY (every kept pair too:
  ``tgsis.db.compare.compare_stored(..., pairs=True)``),
- the baseline of the same answer in Python: ``fetch_feature`` of both
  meshes and ``tgsis.compare_meshes``,
- after ``enable_feature_versioning``: the original surface with 1 % of its
  vertices moved through the view in a child version,
  ``tgsis.compare_geometry_versions(geoid, 'DEFAULT', 'edit')``.

Every answer is checked against ``compare_meshes`` first. tgsis is installed
from this checkout's SQL (``method="sql"``) into a throwaway cluster.

    python bench/compare_sql.py [--side 1000] [--repeat 3]       # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis.db.compare import GeometryChanges, compare_stored, compare_versions

Conn = psycopg.Connection[Any]


def edited(surface: tgsis.Surface, rng: np.random.Generator) -> tgsis.Surface:
    """Shuffled, 1 % of the vertices moved up, 0.1 % of the triangles reversed."""
    vertices, triangles = surface.vertices.copy(), surface.cells.copy()
    moved = rng.choice(len(vertices), len(vertices) // 100, replace=False)
    vertices[moved, 2] += 1.0
    flipped = rng.choice(len(triangles), len(triangles) // 1000, replace=False)
    triangles[flipped] = triangles[flipped][:, [1, 0, 2]]
    order = rng.permutation(len(vertices))
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    return tgsis.Surface(vertices[order], position[triangles][rng.permutation(len(triangles))], name="edited")


def same(got: GeometryChanges, diff: tgsis.MeshDiff) -> bool:
    """The SQL answer equals compare_meshes' (stored ids are mesh indices after a fresh upload)."""
    return (
        got.counts() == diff.counts()
        and np.array_equal(got.vertices_removed, diff.removed_vertices)
        and np.array_equal(got.vertices_added, diff.added_vertices)
        and np.array_equal(got.cells_removed, diff.removed_cells)
        and np.array_equal(got.cells_added, diff.added_cells)
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    rng = np.random.default_rng(1)
    old = grid_surface(args.side)
    old = tgsis.Surface(old.vertices, old.cells, name="bench")
    new = edited(old, rng)
    diff = tgsis.compare_meshes(old, new)
    print(f"surface: {old.n_vertices} vertices, {old.n_cells} triangles; edited copy: {diff}")
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "horizons", "SURFACE")
        a = tgsis.insert_feature(conn, "horizons", old)
        b = tgsis.insert_feature(conn, "horizons", new)
        conn.commit()
        conn.autocommit = True
        for table in ("tgsis.vrtx", "tgsis.trgl", "tgsis.geometry"):
            conn.execute(f"VACUUM ANALYZE {table}")
        conn.autocommit = False

        assert same(compare_stored(conn, a, b), diff) and same(compare_stored(conn, a, b, pairs=True), diff)

        def fetch(geoid: int) -> tgsis.Mesh:
            mesh = tgsis.fetch_feature(conn, "horizons", geoid).mesh
            assert isinstance(mesh, tgsis.Mesh)
            return mesh

        def committed(action: Callable[[], object]) -> Callable[[], None]:
            def run() -> None:
                action()
                conn.commit()

            return run

        summary_s, pairs_s, python_s = paired(
            [
                committed(lambda: compare_stored(conn, a, b)),
                committed(lambda: compare_stored(conn, a, b, pairs=True)),
                committed(lambda: tgsis.compare_meshes(fetch(a), fetch(b))),
            ],
            args.repeat,
        )

        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "edit")
        with tgsis.in_version(conn, "edit"):
            conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid %% 100 = 0", (a,))
            conn.commit()
            child = fetch(a)
        assert same(compare_versions(conn, a, "DEFAULT", "edit"), tgsis.compare_meshes(old, child))
        conn.commit()
        (versions_s,) = paired([committed(lambda: compare_versions(conn, a, "DEFAULT", "edit"))], args.repeat)

    print(f"compare_geometries (summary, ids of removed/added):   {summary_s:6.2f} s")
    print(f"geometry_changes by COPY (every kept pair too):        {pairs_s:6.2f} s")
    print(f"Python: fetch_feature x 2 + compare_meshes:            {python_s:6.2f} s")
    print(f"compare_geometry_versions, 1 % moved in a child:       {versions_s:6.2f} s")
    print(f"compare_geometries_s: {summary_s:.3f}")
    print(f"geometry_changes_copy_s: {pairs_s:.3f}")
    print(f"python_fetch_compare_s: {python_s:.3f}")
    print(f"compare_geometry_versions_s: {versions_s:.3f}")


if __name__ == "__main__":
    main()
