"""Interpolation set-up helpers on a 100k-vertex disk: topology, borders, one-rings, disk check, cut, partition.

The disk is a 317 x 317 grid (100,489 vertices, 199,712 triangles) with its
vertices renumbered and its triangles shuffled, as a mesh read from a file
would be. Every figure starts from a fresh :class:`MeshTopology` (nothing
cached) unless it says otherwise. Baseline: the border walk written as a Python
loop over a successor dictionary (the spec's 0.5 s figure).

Run: ``python bench/interp_topology.py`` (no database).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from timing import timed

from tgsis.interpolation import (
    MeshTopology,
    border_loops,
    check_disk,
    cut_along_paths,
    one_rings,
    partition_pair,
    partition_surface,
    shortest_edge_path,
)
from tgsis.mesh import Surface

SIDE = 317
REPEAT = 3


def disk(seed: int = 1) -> tuple[Surface, npt.NDArray[np.int64]]:
    """The shuffled grid and the new index of each grid vertex (row-major)."""
    u, v = np.meshgrid(np.arange(SIDE, dtype=float), np.arange(SIDE, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), 3 * np.sin(u.ravel() / 40) * np.cos(v.ravel() / 50)], 1)
    idx = np.arange(SIDE * SIDE).reshape(SIDE, SIDE)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    tri = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    rng = np.random.default_rng(seed)
    new_of_old = rng.permutation(SIDE * SIDE).astype(np.int64)
    shuffled = np.empty_like(vertices)
    shuffled[new_of_old] = vertices
    return Surface(shuffled, new_of_old[tri][rng.permutation(len(tri))]), new_of_old


def python_border_walk(surface: Surface) -> list[list[int]]:
    """Baseline: border edges counted in a dictionary, loops walked one vertex at a time."""
    count: dict[tuple[int, int], int] = {}
    for t in surface.triangles.tolist():
        for p, q in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            key = (p, q) if p < q else (q, p)
            count[key] = count.get(key, 0) + 1
    succ = {}
    for t in surface.triangles.tolist():
        for p, q in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            if count[(p, q) if p < q else (q, p)] == 1:
                succ[p] = q
    loops, seen = [], set()
    for start in succ:
        if start in seen:
            continue
        loop, here = [start], succ[start]
        seen.add(start)
        while here != start:
            loop.append(here)
            seen.add(here)
            here = succ[here]
        loops.append(loop)
    return loops


def main() -> None:
    surface, at = disk()

    def g(c: int, r: int) -> int:
        return int(at[r * SIDE + c])

    print(f"disk: {surface.n_vertices} vertices, {surface.n_cells} triangles (renumbered, shuffled)")
    figures: dict[str, float] = {}

    figures["edges_ms"] = 1000 * timed(lambda: MeshTopology.of(surface).edges, REPEAT)
    figures["border_loops_ms"] = 1000 * timed(lambda: border_loops(surface), REPEAT)
    cached = MeshTopology.of(surface)
    cached.edges  # noqa: B018 - built once before the timed runs
    figures["border_loops_given_edges_ms"] = 1000 * timed(
        lambda: (cached.__dict__.pop("border_loops", None), cached.border_loops), REPEAT
    )
    figures["python_border_walk_ms"] = 1000 * timed(lambda: python_border_walk(surface), REPEAT)
    figures["one_rings_ms"] = 1000 * timed(lambda: one_rings(surface), REPEAT)
    figures["check_disk_ms"] = 1000 * timed(lambda: check_disk(surface), REPEAT)
    figures["shortest_edge_path_ms"] = 1000 * timed(
        lambda: shortest_edge_path(cached, g(0, 0), g(SIDE - 1, SIDE - 1)), REPEAT
    )
    crack = [g(c, SIDE // 2) for c in range(50, SIDE - 50)]
    figures["cut_both_inside_ms"] = 1000 * timed(lambda: cut_along_paths(surface, [crack]), REPEAT)
    mid, last = SIDE // 2, SIDE - 1
    controls = [
        g(0, 0),
        g(mid, 0),
        g(last, 0),
        g(last, mid),
        g(last, last),
        g(mid, last),
        g(0, last),
        g(0, mid),
        g(mid, mid),
    ]
    fences = [
        [g(c, mid) for c in range(0, mid + 1)],
        [g(c, mid) for c in range(mid, last + 1)],
        [g(mid, r) for r in range(0, mid + 1)],
        [g(mid, r) for r in range(mid, last + 1)],
    ]
    part = partition_surface(surface, controls, fences)
    assert len(part.patches) == 4
    figures["partition_4_patches_ms"] = 1000 * timed(lambda: partition_surface(surface, controls, fences), REPEAT)
    figures["partition_pair_ms"] = 1000 * timed(
        lambda: partition_pair(surface, surface, controls, controls, fences, fences), REPEAT
    )

    baseline = figures["python_border_walk_ms"]
    assert len(python_border_walk(surface)) == len(border_loops(surface)) == 1
    print(
        f"border loops, fresh topology: {figures['border_loops_ms'] / baseline:.2f} x the Python walk; "
        f"with edges known: {figures['border_loops_given_edges_ms'] / baseline:.4f} x"
    )
    for name, value in figures.items():
        print(f"{name}: {value:.1f}")


if __name__ == "__main__":
    main()
