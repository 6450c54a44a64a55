"""A class's vector property in chunks: the client's codec against the server's path (issue 40, plan L area C).

A grid surface of ``--side`` squared vertices with one vector property ``normal`` (three doubles a vertex,
random: incompressible) in a class whose properties are in chunks (``tgsis.store_class_in_chunks`` while
empty). ``insert_feature`` and ``fetch_feature`` are timed twice in turn (``--repeat`` times, medians): with
the client's chunk codec (``client``: the chunks encoded in numpy, one binary COPY and
``tgsis.write_property_chunks``; read back as chunk rows and decoded here) and with the path vector
classes took before it (``server``: the client's layout switched off, so the upload writes each object's rows
by ``tgsis.write_property_rows`` and the download reads the face, decoded by the server). A ``bare`` class (no
property) gives the mesh's own share, subtracted. Prints ``name: value`` lines.

    TGSIS_PG=system PYTHONPATH=src:bench .venv/bin/python bench/vector_chunks.py [--side 300] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from timing import bench_database
from transfer import grid_surface

import tgsis
import tgsis.db._property_chunks as property_chunks
from tgsis.db import features as F


def timed(action: Callable[[], Any]) -> float:
    """Seconds of one call."""
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    grid = grid_surface(args.side)
    n = grid.n_vertices
    normal = np.random.default_rng(1).random((n, 3))
    mesh = tgsis.Surface(grid.vertices, grid.cells, vertex_properties={"normal": normal})
    bare = tgsis.Surface(grid.vertices, grid.cells)
    layout = property_chunks._property_layout
    times: dict[str, list[float]] = {}
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "bare", "SURFACE")
        for name in ("client", "server"):
            tgsis.create_feature_class(conn, name, "SURFACE", cell_properties=[("normal", "double precision", 3)])
            conn.execute("SELECT tgsis.store_class_in_chunks(%s)", (name,))
        conn.commit()
        for _ in range(args.repeat):
            for name, surface in (("bare", bare), ("client", mesh), ("server", mesh)):
                property_chunks._property_layout = (lambda *a: None) if name == "server" else layout  # type: ignore[assignment]
                try:
                    geoid = 0

                    def upload(name: str = name, surface: Any = surface) -> None:
                        nonlocal geoid
                        geoid = F.insert_feature(conn, name, surface)
                        conn.commit()

                    times.setdefault(f"{name}_insert", []).append(timed(upload))
                    got: list[Any] = []
                    times.setdefault(f"{name}_fetch", []).append(
                        timed(lambda name=name: got.append(F.fetch_feature(conn, name, geoid).mesh))  # type: ignore[misc]
                    )
                    conn.commit()
                    if name != "bare":
                        back = got[0].vertex_properties["normal"]
                        assert back.shape == (n, 3) and np.array_equal(back.view(np.uint8), normal.view(np.uint8))
                finally:
                    property_chunks._property_layout = layout  # type: ignore[assignment]
    print(f"vertices: {n}")
    medians = {k: statistics.median(v) for k, v in times.items()}
    for key in ("insert", "fetch"):
        for name in ("bare", "client", "server"):
            print(f"{name}_{key}_s: {medians[f'{name}_{key}']:.3f}")
        client = medians[f"client_{key}"] - medians[f"bare_{key}"]
        server = medians[f"server_{key}"] - medians[f"bare_{key}"]
        print(f"property_{key}_client_s: {client:.3f}")
        print(f"property_{key}_server_s: {server:.3f}")
        print(f"property_{key}_server_over_client: {server / client:.2f}" if client > 0 else "")


if __name__ == "__main__":
    main()
