"""The browser view draws a conflicting object's merge regions on the mesh with their solutions (issue 39, item 3).

What is sent (tgsis.view.regions, pure): per region its index, what happens
there (merges by itself from the parent / the child / identical on both sides,
conflict unsolved or solved with parent, child, base, average, manual), each
side's changed ids and largest displacement, and the region's vertices and cells
(margin included) as positions in the drawn mesh's arrays — never a copy of the
mesh, and in the drawn mesh's own (stored) numbering even where the merge
renumbered the child's new ids. Then the endpoint against ``tgsis.object_merge``
of the same database, and the page in headless Chromium: the legend, the table
of regions, each region's colour on the canvas where the region is, and the
facts of the region under the pointer.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface, make_fault, move
from tests.view_helpers import canvas_pixels, chromium, get, running_view, wait_drawn, watched_page
from tgsis.drawing import tetra_boundary
from tgsis.errors import InvalidInputError
from tgsis.merge3 import MeshMerge, MeshState, three_way_merge
from tgsis.testing import TestServer
from tgsis.view.meshes import pack, unpack
from tgsis.view.regions import REGION_STATES, edit_flags, region_drawing, region_state

# four vertices of the 12 x 12 fault, far enough apart that their one-ring regions never touch
CHILD_ONLY, PARENT_ONLY, IDENTICAL, CONFLICT = 2 * SIDE + 2, 2 * SIDE + 9, 9 * SIDE + 2, 9 * SIDE + 9


def _grid_state(side: int = SIDE) -> MeshState:
    surface = curved_surface() if side == SIDE else tgsis.Surface(*_flat(side))
    return MeshState.from_mesh(surface, name="fault")


def _flat(side: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], 1), np.concatenate(
        [np.stack([a, b, d], 1), np.stack([a, d, c], 1)]
    )


def _moved(state: MeshState, ids: npt.ArrayLike, dz: float) -> MeshState:
    vertices = state.vertices.copy()
    vertices[np.searchsorted(state.vertex_ids, ids), 2] += dz
    return MeshState(
        state.cell_size,
        state.vertex_ids,
        vertices,
        state.cell_ids,
        state.cells,
        state.vertex_properties,
        state.cell_properties,
        state.name,
    )


def _four_regions() -> MeshMerge:
    base = _grid_state()
    parent = _moved(_moved(_moved(base, [PARENT_ONLY], 40.0), [IDENTICAL], 7.0), [CONFLICT], 80.0)
    child = _moved(_moved(_moved(base, [CHILD_ONLY], 50.0), [IDENTICAL], 7.0), [CONFLICT], 30.0)
    return three_way_merge(base, parent, child)


def _region_with(merge: MeshMerge, vertex: int) -> int:
    (found,) = [
        r.index for r in merge.regions if vertex in r.vertex_ids and len(r.parent_vertex_ids) + len(r.child_vertex_ids)
    ]
    return found


def _split(arrays: dict[str, Any], regions: list[dict[str, Any]], what: str) -> list[npt.NDArray[np.int64]]:
    """Each region's positions in the flat array ``region_<what>`` (regions one after the other, counts in the header)."""
    flat = np.asarray(arrays[f"region_{what}"], dtype=np.int64)
    ends = np.cumsum([r["drawn"][what] for r in regions])
    assert ends[-1] == len(flat) if len(ends) else len(flat) == 0
    return np.split(flat, ends[:-1])


# --------------------------------------------------------------------------- the data (pure)


def test_each_region_is_its_drawn_vertices_and_cells_and_what_happens_there() -> None:
    merge = _four_regions()
    child = merge.child
    # the drawn mesh in an order of its own: positions, not ids, reach the browser
    order = np.random.default_rng(1).permutation(child.n_vertices)
    corder = np.random.default_rng(2).permutation(child.n_cells)
    regions, arrays = region_drawing(merge, child.vertex_ids[order], child.cell_ids[corder])
    assert set(arrays) == {"region_vertices", "region_cells"}
    assert [r["index"] for r in regions] == [r.index for r in merge.regions]
    states = {r["index"]: r["state"] for r in regions}
    assert states == {
        _region_with(merge, CHILD_ONLY): "merges-child",
        _region_with(merge, PARENT_ONLY): "merges-parent",
        _region_with(merge, IDENTICAL): "merges-both",
        _region_with(merge, CONFLICT): "unsolved",
    }
    solutions = {r["index"]: r["solution"] for r in regions}
    assert solutions[_region_with(merge, CONFLICT)] == "unsolved"
    assert {s for i, s in solutions.items() if i != _region_with(merge, CONFLICT)} == {"automatic"}
    vertices, cells = _split(arrays, regions, "vertices"), _split(arrays, regions, "cells")
    for sent, region, v, c in zip(regions, merge.regions, vertices, cells):
        # margin included: every vertex and cell of the region, found at its place in the drawn arrays
        assert sorted(child.vertex_ids[order][v].tolist()) == region.vertex_ids.tolist()
        assert sorted(child.cell_ids[corder][c].tolist()) == region.cell_ids.tolist()
        assert sent["drawn"] == {"vertices": len(region.vertex_ids), "cells": len(region.cell_ids)}
        assert sent["missing"] == {"vertices": 0, "cells": 0}
        assert sent["conflict"] is region.conflict and sent["changed_by"] == region.sides
        for side in ("parent", "child"):
            assert sent[side]["vertices"] == len(getattr(region, f"{side}_vertex_ids"))
            assert sent[side]["cells"] == len(getattr(region, f"{side}_cell_ids"))
            assert sent[side]["largest_displacement"] == getattr(region, f"{side}_displacement")
        assert sent["bounds"] == region.bounds.tolist()
    conflict = regions[_region_with(merge, CONFLICT)]
    assert conflict["parent"]["largest_displacement"] == 80.0 and conflict["child"]["largest_displacement"] == 30.0
    # the moved vertex and its one ring of cells (the margin) on the grid
    assert (len(vertices[_region_with(merge, CONFLICT)]), len(cells[_region_with(merge, CONFLICT)])) == (1, 6)
    json.dumps(regions, allow_nan=False)  # the header is strict JSON


def test_the_recorded_solutions_are_shown_and_bad_ones_refused() -> None:
    merge = _four_regions()
    conflict = _region_with(merge, CONFLICT)
    ids = merge.child.vertex_ids, merge.child.cell_ids
    for solution in ("parent", "child", "base", "average", "manual", "unsolved"):
        regions, _ = region_drawing(merge, *ids, {conflict: solution})
        assert regions[conflict]["solution"] == solution
        assert regions[conflict]["state"] == ("unsolved" if solution == "unsolved" else f"solved-{solution}")
    automatic = _region_with(merge, PARENT_ONLY)
    regions, _ = region_drawing(merge, *ids, {automatic: "automatic"})
    assert regions[automatic]["state"] == "merges-parent"
    with pytest.raises(InvalidInputError, match=f"region {automatic} merges by itself"):
        region_drawing(merge, *ids, {automatic: "child"})
    with pytest.raises(InvalidInputError, match=f"region {conflict} .*'automatic'"):
        region_drawing(merge, *ids, {conflict: "automatic"})
    with pytest.raises(InvalidInputError, match="'mine'"):
        region_drawing(merge, *ids, {conflict: "mine"})
    with pytest.raises(InvalidInputError, match="no region 99"):
        region_drawing(merge, *ids, {99: "parent"})
    # every state has a place in the legend, and the states are told apart
    assert set(REGION_STATES) == {
        "merges-parent",
        "merges-child",
        "merges-both",
        "unsolved",
        "solved-parent",
        "solved-child",
        "solved-base",
        "solved-average",
        "solved-manual",
    }
    assert region_state(merge.regions[conflict], "average") == "solved-average"


def test_the_regions_are_drawn_in_the_stored_numbering_where_the_merge_renumbered_the_child() -> None:
    """Both sides add a vertex and a triangle with the same new ids, elsewhere: the merge renumbers the child's.

    The drawn mesh is the child as stored: its vertex 144 is the child's new
    vertex, which the parent's region (whose 144 is the parent's vertex) must
    not colour.
    """
    base = _grid_state()
    n, m = base.n_vertices, base.n_cells

    def added(state: MeshState, where: tuple[float, float, float], corner: int) -> MeshState:
        # a new vertex beside a boundary edge of the grid (corner, corner + 1) and a triangle on them
        return MeshState(
            3,
            np.append(state.vertex_ids, n),
            np.vstack([state.vertices, where]),
            np.append(state.cell_ids, m),
            np.vstack([state.cells, [corner, corner + 1, n]]),
            {k: np.append(v, 0.5) for k, v in state.vertex_properties.items()},
            {k: np.append(v, 1) for k, v in state.cell_properties.items()},
            state.name,
        )

    parent = added(base, (1500.0, -300.0, 0.0), 5)  # south edge
    child = added(base, (1500.0, 3000.0, 0.0), SIDE * (SIDE - 1) + 5)  # north edge
    merge = three_way_merge(base, parent, child)
    assert merge.child_vertex_renumbering.tolist() == [[n, n + 1]]
    stored_child = child  # what the view draws: the version's rows, ids as stored
    regions, arrays = region_drawing(merge, stored_child.vertex_ids, stored_child.cell_ids)
    by_side = {r["changed_by"]: r for r in regions}
    vertices = dict(zip([r["changed_by"] for r in regions], _split(arrays, regions, "vertices")))
    cells = dict(zip([r["changed_by"] for r in regions], _split(arrays, regions, "cells")))
    assert set(by_side) == {"parent", "child"}
    # the child's new vertex and triangle are in the child's region, at their stored places
    assert n in stored_child.vertex_ids[vertices["child"]] and m in stored_child.cell_ids[cells["child"]]
    # the parent's region: not the child's vertex 144 (the parent's own 144 is not in the drawn mesh)
    assert n not in stored_child.vertex_ids[vertices["parent"]]
    assert m not in stored_child.cell_ids[cells["parent"]]
    assert by_side["parent"]["missing"] == {"vertices": 1, "cells": 1}
    assert by_side["child"]["missing"] == {"vertices": 0, "cells": 0}
    # who changed each drawn vertex: the child's 144 is the child's (1), not the parent's (2)
    flags = edit_flags(merge, stored_child.vertex_ids)
    assert flags[np.searchsorted(stored_child.vertex_ids, n)] == 1
    assert set(np.flatnonzero(flags == 2).tolist()) == {5, 6}  # the corners of the parent's new triangle it draws
    assert set(stored_child.vertex_ids[flags == 1].tolist()) == {SIDE * (SIDE - 1) + 5, SIDE * (SIDE - 1) + 6, n}


def test_the_bytes_sent_follow_the_regions_not_the_mesh() -> None:
    """Two 1,000-vertex regions cost the same on a 100 x 100 and a 300 x 300 grid: ids of the region, no mesh copy."""
    sizes = []
    for side in (100, 300):
        base = _grid_state(side)
        # 1,000 moved vertices in a 25 x 40 block in each of two far corners
        block = (np.arange(25)[:, None] * side + np.arange(40)[None, :]).ravel() + 2 * side + 2
        far = (np.arange(25)[:, None] * side + np.arange(40)[None, :]).ravel() + (side - 28) * side + side - 43
        merge = three_way_merge(base, _moved(base, block, 1.0), _moved(base, far, 2.0))
        assert [len(r.parent_vertex_ids) + len(r.child_vertex_ids) for r in merge.regions] == [1000, 1000]
        regions, arrays = region_drawing(merge, merge.child.vertex_ids, merge.child.cell_ids)
        sizes.append(len(pack({"regions": regions}, arrays)) - len(pack({}, {})))
    assert abs(sizes[0] - sizes[1]) <= 64  # the header's numbers (bounds) may have a digit more or less
    # about 1,100 vertices and 2,200 triangles per region (margin included), 4 bytes each, and a short header
    assert sizes[0] < 2 * (1200 + 2400) * 4 + 2000


# --------------------------------------------------------------------------- the endpoint and the page


@pytest.fixture(scope="module")
def regions_view(pg: TestServer, template_db: str) -> Iterator[tuple[str, int, str]]:
    """The curved fault with the four regions of :func:`_four_regions` between e1 and DEFAULT, and the view."""
    with pg.database("tgsis_view_regions", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            geoid = make_fault(conn)
            move(conn, "e1", geoid, [CHILD_ONLY], (0.0, 0.0, 50.0))
            move(conn, "DEFAULT", geoid, [PARENT_ONLY], (0.0, 0.0, 40.0))
            move(conn, "e1", geoid, [IDENTICAL], (0.0, 0.0, 7.0))
            move(conn, "DEFAULT", geoid, [IDENTICAL], (0.0, 0.0, 7.0))
            move(conn, "e1", geoid, [CONFLICT], (0.0, 0.0, 30.0))
            move(conn, "DEFAULT", geoid, [CONFLICT], (0.0, 0.0, 80.0))
        with running_view(dsn) as url:
            yield url, geoid, dsn


def test_the_conflict_endpoint_sends_the_regions_of_object_merge(regions_view: tuple[str, int, str]) -> None:
    url, geoid, dsn = regions_view
    status, body, kind = get(f"{url}/api/conflict/{geoid}?version=e1")
    assert status == 200 and kind == "application/octet-stream", body[:300]
    header, arrays = unpack(body)
    with psycopg.connect(dsn) as conn:
        merge = tgsis.object_merge(conn, "e1", geoid)
    assert header["merges_by_region"] is True
    regions = header["regions"]
    assert [(r["index"], r["changed_by"], r["conflict"]) for r in regions] == [
        (r.index, r.sides, r.conflict) for r in merge.regions
    ]
    assert sorted(r["state"] for r in regions) == ["merges-both", "merges-child", "merges-parent", "unsolved"]
    origin = np.asarray(header["origin"])
    positions = arrays["positions"].reshape(-1, 3).astype(np.float64) + origin
    triangles = arrays["indices"].reshape(-1, 3)
    for sent, region, v, c in zip(
        regions, merge.regions, _split(arrays, regions, "vertices"), _split(arrays, regions, "cells")
    ):
        # the positions sent are the region's vertices as the version holds them (float32 around the origin)
        expected = merge.child.vertices[np.searchsorted(merge.child.vertex_ids, region.vertex_ids)]
        np.testing.assert_allclose(np.sort(positions[v], axis=0), np.sort(expected, axis=0), atol=1e-3)
        # and its triangles are the ones on those vertices' stored corners
        corners = merge.child.cells[np.searchsorted(merge.child.cell_ids, region.cell_ids)]
        drawn = np.sort(positions[triangles[c]].round(2).reshape(len(c), -1), axis=0)
        want = np.sort(
            merge.child.vertices[np.searchsorted(merge.child.vertex_ids, corners)].round(2).reshape(len(c), -1), axis=0
        )
        np.testing.assert_allclose(drawn, want, atol=0.02)
        assert sent["solution"] == ("unsolved" if region.conflict else "automatic")


def test_who_changed_each_vertex_comes_from_the_merge_of_an_object_that_merges_by_region(
    regions_view: tuple[str, int, str],
) -> None:
    """The per-vertex ``changed`` flags of such an object are the merge's id-keyed edits (1 child, 2 parent, 3 both).

    Not a comparison of the meshes by content (``compare_versions`` twice,
    tens of seconds on a 10,000-vertex surface): the merge the regions come
    from already knows each side's edit.
    """
    url, geoid, dsn = regions_view
    _, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
    header, arrays = unpack(body)
    with psycopg.connect(dsn) as conn:
        merge = tgsis.object_merge(conn, "e1", geoid)
    flags = np.asarray(arrays["changed"]).astype(int)
    drawn = merge.child.vertex_ids  # the drawn vertices are the version's, in id order (no renumbering here)
    expected = {CHILD_ONLY: 1, PARENT_ONLY: 2, IDENTICAL: 3, CONFLICT: 3}
    assert {int(drawn[i]): int(flags[i]) for i in np.flatnonzero(flags)} == expected
    assert header["child_changes"] == {"vertices": 3, "cells": 0}
    assert header["parent_changes"] == {"vertices": 3, "cells": 0}


def test_an_object_that_merges_as_a_whole_only_says_why(pg: TestServer, template_db: str) -> None:
    """A feature property changed on both sides: no regions, the reason in the header; the page still draws."""
    with pg.database("tgsis_view_whole", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"unit": "text"})
            tgsis.enable_feature_versioning(conn)
            fault = curved_surface()
            geoid = tgsis.insert_feature(conn, "faults", tgsis.Surface(fault.vertices, fault.cells), {"unit": "A"})
            tgsis.create_version(conn, "e1")
            conn.commit()
            with tgsis.in_version(conn, "e1"):
                conn.execute("UPDATE faults SET unit = 'B' WHERE _geoid = %s", (geoid,))
                conn.commit()
            conn.execute("UPDATE faults SET unit = 'C' WHERE _geoid = %s", (geoid,))
            conn.commit()
        with running_view(dsn) as url:
            status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
    assert status == 200, body[:300]
    header, arrays = unpack(body)
    assert header["merges_by_region"] is False and header["regions"] == []
    assert "attributes" in header["reason"] or "propert" in header["reason"], header["reason"]
    assert len(arrays["region_vertices"]) == 0 and len(arrays["region_cells"]) == 0


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    with watched_page(browser, 1100, 1200) as page:
        yield page


def _rgb(css: str) -> npt.NDArray[np.int64]:
    return np.array([int(x) for x in css.strip("rgba() ").split(",")[:3]])


def _near(pixels: npt.NDArray[np.uint8], rgb: npt.NDArray[np.int64], tolerance: int = 6) -> npt.NDArray[np.bool_]:
    near: npt.NDArray[np.bool_] = np.abs(pixels.astype(np.int64) - rgb).max(axis=2) <= tolerance
    return near


def test_the_page_draws_each_region_in_the_colour_of_what_happens_there(
    regions_view: tuple[str, int, str], page: Any
) -> None:
    url, geoid, _ = regions_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)
    # the legend: one entry per state, each its own colour
    legend = {
        k: _rgb(c)
        for k, c in page.locator("#region-legend [data-state]").evaluate_all(
            "items => items.map(i => [i.dataset.state, getComputedStyle(i.querySelector('.swatch')).backgroundColor])"
        )
    }
    assert set(legend) == set(REGION_STATES)
    assert len({tuple(c) for c in legend.values()}) == len(legend)
    # the table of regions: what happens, the solution, each side's counts and largest displacement
    rows = page.locator("#regions tbody tr").evaluate_all(
        "rows => rows.map(r => [r.dataset.feature, r.dataset.region, r.dataset.state, r.textContent])"
    )
    assert sorted(r[2] for r in rows) == ["merges-both", "merges-child", "merges-parent", "unsolved"]
    assert {r[0] for r in rows} == {str(geoid)}
    (conflict,) = [r for r in rows if r[2] == "unsolved"]
    assert "unsolved" in conflict[3] and "80" in conflict[3] and "30" in conflict[3]
    # each region's colour is on the canvas, inside the box the region's vertices project to
    pixels = canvas_pixels(page)
    boxes = json.loads(page.evaluate("document.body.dataset.regionBoxes"))
    for feature, region, state, _ in rows:
        mask = _near(pixels, legend[state])
        assert mask.sum() >= 20, f"region {region} ({state}): {mask.sum()} pixels of its colour"
        x0, y0, x1, y1 = boxes[f"{feature}:{region}"]
        ys, xs = np.nonzero(mask)
        inside = (xs >= x0 - 3) & (xs <= x1 + 3) & (ys >= y0 - 3) & (ys <= y1 + 3)
        assert inside.mean() > 0.95, f"region {region} ({state}): its colour outside its place"
    # the states no region of this object is in are not drawn
    for state in set(REGION_STATES) - {r[2] for r in rows}:
        assert _near(pixels, legend[state], 3).sum() == 0, state


def test_the_facts_of_the_region_under_the_pointer(regions_view: tuple[str, int, str], page: Any) -> None:
    url, geoid, _ = regions_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)
    boxes = json.loads(page.evaluate("document.body.dataset.regionBoxes"))
    rows = page.locator("#regions tbody tr").evaluate_all("rows => rows.map(r => [r.dataset.region, r.dataset.state])")
    (region,) = [r for r, s in rows if s == "unsolved"]
    unsolved = _rgb(
        page.locator("#region-legend [data-state=unsolved] .swatch").evaluate(
            "s => getComputedStyle(s).backgroundColor"
        )
    )
    pixels = canvas_pixels(page)
    ys, xs = np.nonzero(_near(pixels, unsolved))
    pick = int(np.argmin((xs - xs.mean()) ** 2 + (ys - ys.mean()) ** 2))  # a pixel of the region near its middle
    canvas = page.locator("#scene").bounding_box()
    page.mouse.move(canvas["x"] + xs[pick] + 0.5, canvas["y"] + ys[pick] + 0.5)
    info = page.locator("#region-info")
    info.wait_for(state="visible")
    text = info.text_content()
    assert f"feature {geoid} region {region}" in text
    assert "conflict, unsolved" in text
    assert "parent changed 1 vertex" in text and "largest displacement 80" in text
    assert "child changed 1 vertex" in text and "largest displacement 30" in text
    # away from every region: nothing under the pointer
    x0, y0, x1, y1 = boxes[f"{geoid}:{region}"]
    page.mouse.move(canvas["x"] + 2, canvas["y"] + 2)
    assert "no region" in info.text_content() or not info.is_visible()
    # a click pins the region and marks its row
    page.mouse.click(canvas["x"] + xs[pick] + 0.5, canvas["y"] + ys[pick] + 0.5)
    assert page.locator(f"#regions tr.picked[data-region='{region}']").count() == 1
    assert x0 <= xs[pick] <= x1 and y0 <= ys[pick] <= y1


# --------------------------------------------------------------------------- recorded solutions (tgsis.conflict_regions)

# six conflicting vertices, one region each, apart: rows 2 and 5, columns 2, 5 and 8 of the grid
SOLVED = {"parent": 2 * SIDE + 2, "child": 2 * SIDE + 5, "base": 2 * SIDE + 8, "average": 5 * SIDE + 2}
MANUAL, UNSOLVED = 5 * SIDE + 5, 5 * SIDE + 8


def _six_conflicts(conn: psycopg.Connection[Any]) -> tuple[int, dict[str, int]]:
    """The fault with six conflicting regions in e1, five solved (one per solution) and one not: (geoid, region of each)."""
    geoid = make_fault(conn)
    for vertex in [*SOLVED.values(), MANUAL, UNSOLVED]:
        move(conn, "e1", geoid, [vertex], (0.0, 0.0, 30.0))
        move(conn, "DEFAULT", geoid, [vertex], (0.0, 0.0, -45.0))
    tgsis.find_conflicts(conn, "e1")
    merge = tgsis.object_merge(conn, "e1", geoid)
    region = {name: _region_with(merge, vertex) for name, vertex in [*SOLVED.items(), ("manual", MANUAL)]}
    region["unsolved"] = _region_with(merge, UNSOLVED)
    for solution, index in region.items():
        if solution in SOLVED:
            tgsis.resolve_region(conn, "e1", geoid, index, solution)
    # manual: the parent's rows with the region's vertex put 12 m above its base position
    parent = merge.parent
    vertices = parent.vertices.copy()
    vertices[np.searchsorted(parent.vertex_ids, MANUAL), 2] += 45.0 + 12.0
    manual = MeshState(
        3,
        parent.vertex_ids,
        vertices,
        parent.cell_ids,
        parent.cells,
        parent.vertex_properties,
        parent.cell_properties,
        parent.name,
    )
    tgsis.resolve_region(conn, "e1", geoid, region["manual"], "manual", manual)
    conn.commit()
    return geoid, region


@pytest.fixture(scope="module")
def solved_view(pg: TestServer, template_db: str) -> Iterator[tuple[str, int, dict[str, int], str]]:
    with pg.database("tgsis_view_solved", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            geoid, region = _six_conflicts(conn)
        with running_view(dsn) as url:
            yield url, geoid, region, dsn


def test_the_endpoint_sends_the_recorded_solution_of_each_region(
    solved_view: tuple[str, int, dict[str, int], str],
) -> None:
    url, geoid, region, _ = solved_view
    status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
    assert status == 200, body[:300]
    header, _ = unpack(body)
    assert header["solutions"] == "recorded"
    sent = {r["index"]: (r["solution"], r["state"]) for r in header["regions"]}
    for solution, index in region.items():
        assert sent[index] == (solution, "unsolved" if solution == "unsolved" else f"solved-{solution}")


def test_the_page_draws_each_solution_in_its_colour(
    solved_view: tuple[str, int, dict[str, int], str], page: Any
) -> None:
    url, geoid, region, _ = solved_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)
    legend = {
        k: _rgb(c)
        for k, c in page.locator("#region-legend [data-state]").evaluate_all(
            "items => items.map(i => [i.dataset.state, getComputedStyle(i.querySelector('.swatch')).backgroundColor])"
        )
    }
    rows = page.locator("#regions tbody tr").evaluate_all(
        "rows => rows.map(r => [r.dataset.region, r.dataset.state, r.children[3].textContent])"
    )
    assert sorted((int(i), s, text) for i, s, text in rows) == sorted(
        (index, "unsolved" if name == "unsolved" else f"solved-{name}", name) for name, index in region.items()
    )
    pixels = canvas_pixels(page)
    boxes = json.loads(page.evaluate("document.body.dataset.regionBoxes"))
    for index, state, _ in rows:
        mask = _near(pixels, legend[state])
        assert mask.sum() >= 20, f"region {index} ({state}): {mask.sum()} pixels of its colour"
        x0, y0, x1, y1 = boxes[f"{geoid}:{index}"]
        ys, xs = np.nonzero(mask)
        inside = (xs >= x0 - 3) & (xs <= x1 + 3) & (ys >= y0 - 3) & (ys <= y1 + 3)
        assert inside.mean() > 0.95, f"region {index} ({state}): its colour outside its place"
    for state in ("merges-parent", "merges-child", "merges-both"):
        assert _near(pixels, legend[state], 3).sum() == 0, state
    # the facts under the pointer name the solution
    ys, xs = np.nonzero(_near(pixels, legend["solved-average"]))
    pick = int(np.argmin((xs - xs.mean()) ** 2 + (ys - ys.mean()) ** 2))
    canvas = page.locator("#scene").bounding_box()
    page.mouse.move(canvas["x"] + xs[pick] + 0.5, canvas["y"] + ys[pick] + 0.5)
    page.locator("#region-info").wait_for(state="visible")
    text = page.locator("#region-info").text_content()
    assert f"region {region['average']}: conflict, solved with the average; solution: average" in text


def test_solutions_recorded_on_an_earlier_state_are_not_shown_as_holding(
    db_dsn: str, conn: psycopg.Connection[Any]
) -> None:
    """A new edit after the solutions: the regions are found again; until then the page shows them unsolved, and says why."""
    geoid, region = _six_conflicts(conn)
    move(conn, "e1", geoid, [SOLVED["parent"]], (0.0, 0.0, 1.0))  # the version edits a solved region again
    with running_view(db_dsn) as url:
        _, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
    header, _ = unpack(body)
    assert header["solutions"] == "stale"
    assert {r["solution"] for r in header["regions"]} == {"unsolved"}


# --------------------------------------------------------------------------- lines, points, solids


def _kinds(conn: psycopg.Connection[Any]) -> dict[str, int]:
    """A line set, a point set and a tetrahedral solid, each with a conflict in e1 (vertex 2 moved differently on both
    sides) and an edit of the version's own elsewhere (the last vertex)."""
    tgsis.create_feature_class(conn, "wells", "MULTILINESTRING")
    tgsis.create_feature_class(conn, "samples", "MULTIPOINT")
    tgsis.create_feature_class(conn, "blocks", "MULTITETRA")
    tgsis.enable_feature_versioning(conn)
    x = np.linspace(0.0, 900.0, 10)
    line = tgsis.LineSet(np.stack([x, 0.5 * x, np.sin(x / 100) * 50], 1), [[i, i + 1] for i in range(9)])
    points = tgsis.PointSet(np.stack([x, x[::-1], np.cos(x / 100) * 50], 1))
    u, v, w = np.meshgrid(np.arange(4.0), np.arange(3.0), np.arange(2.0), indexing="ij")
    cube = np.stack([u.ravel(), v.ravel(), w.ravel()], 1) * 100
    from scipy.spatial import Delaunay

    tets = Delaunay(cube).simplices
    solid = tgsis.TetraMesh(cube, tets)
    ids = {
        "wells": tgsis.insert_feature(conn, "wells", line),
        "samples": tgsis.insert_feature(conn, "samples", points),
        "blocks": tgsis.insert_feature(conn, "blocks", solid),
    }
    tgsis.create_version(conn, "e1")
    conn.commit()
    for geoid in ids.values():
        last = conn.execute("SELECT max(vrtxid) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone()
        assert last is not None
        move(conn, "e1", geoid, [2], (0.0, 0.0, 30.0))
        move(conn, "DEFAULT", geoid, [2], (0.0, 0.0, -20.0))
        move(conn, "e1", geoid, [int(last[0])], (0.0, 0.0, 40.0))
    return ids


@pytest.fixture(scope="module")
def kinds_view(pg: TestServer, template_db: str) -> Iterator[tuple[str, dict[str, int], str]]:
    with pg.database("tgsis_view_kinds", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            ids = _kinds(conn)
        with running_view(dsn) as url:
            yield url, ids, dsn


def test_lines_points_and_solids_are_drawn_with_their_regions(kinds_view: tuple[str, dict[str, int], str]) -> None:
    url, ids, dsn = kinds_view
    for name, geoid in ids.items():
        status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1")
        assert status == 200, (name, body[:300])
        header, arrays = unpack(body)
        with psycopg.connect(dsn) as conn:
            merge = tgsis.object_merge(conn, "e1", geoid)
        assert header["kind"] == {"wells": "lines", "samples": "points", "blocks": "triangles"}[name]
        assert sorted(r["state"] for r in header["regions"]) == ["merges-child", "unsolved"], name
        positions = arrays["positions"].reshape(-1, 3).astype(np.float64) + np.asarray(header["origin"])
        for sent, region, v in zip(header["regions"], merge.regions, _split(arrays, header["regions"], "vertices")):
            want = merge.child.vertices[np.searchsorted(merge.child.vertex_ids, region.vertex_ids)]
            np.testing.assert_allclose(np.sort(positions[v], axis=0), np.sort(want, axis=0), atol=1e-3)
            assert sent["missing"] == {"vertices": 0, "cells": 0} or name == "blocks"
        cells = _split(arrays, header["regions"], "cells")
        if name == "wells":  # each region's segments, by their corners
            k = 2
            for region, c in zip(merge.regions, cells):
                corners = merge.child.cells[np.searchsorted(merge.child.cell_ids, region.cell_ids)]
                want = np.sort(
                    merge.child.vertices[np.searchsorted(merge.child.vertex_ids, corners)].reshape(-1, 3 * k), axis=0
                )
                got = positions[arrays["indices"].reshape(-1, k)[c]].reshape(-1, 3 * k)
                np.testing.assert_allclose(np.sort(got, axis=0), want, atol=1e-3)
        if name == "blocks":  # the boundary faces of the region's tetrahedra, every one of them
            faces = merge.child.vertex_ids[arrays["indices"].reshape(-1, 3).astype(np.int64)]
            boundary, owner = tetra_boundary(merge.child.cells)  # the solid's faces, as vertex ids
            for sent, region, c in zip(header["regions"], merge.regions, cells):
                assert len(c) == sent["drawn"]["cells"] > 0
                mine = np.isin(merge.child.cell_ids[owner], region.cell_ids)
                assert sorted(map(sorted, faces[c].tolist())) == sorted(map(sorted, boundary[mine].tolist()))


def test_a_page_of_lines_points_and_a_solid_draws_their_regions(
    kinds_view: tuple[str, dict[str, int], str], page: Any
) -> None:
    url, ids, _ = kinds_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)
    rows = page.locator("#regions tbody tr").evaluate_all("rows => rows.map(r => [r.dataset.feature, r.dataset.state])")
    assert sorted(map(tuple, rows)) == sorted((str(g), s) for g in ids.values() for s in ("merges-child", "unsolved"))
    unsolved = _rgb(
        page.locator("#region-legend [data-state=unsolved] .swatch").evaluate(
            "s => getComputedStyle(s).backgroundColor"
        )
    )
    assert _near(canvas_pixels(page), unsolved).sum() >= 20


def test_a_feature_the_version_deleted_does_not_blank_the_page(
    db_dsn: str, conn: psycopg.Connection[Any], page: Any
) -> None:
    """Deleted in the version, moved in the parent: a conflict with nothing to draw in the version.

    Was: its endpoint answered 404 and the whole page failed, the other
    features' regions undrawn. Now the others are drawn and the page says why
    that one is not.
    """
    from tgsis.db import features as F

    geoid = make_fault(conn)
    fault = curved_surface()
    fault.vertices[:, 0] += 5000.0
    gone = F.insert_feature(conn, "faults", fault)  # in DEFAULT, and so in e1 once refreshed
    conn.commit()
    tgsis.refresh_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, [CONFLICT], (0.0, 0.0, 30.0))
    move(conn, "DEFAULT", geoid, [CONFLICT], (0.0, 0.0, 80.0))
    move(conn, "DEFAULT", gone, [3], (0.0, 0.0, 5.0))
    with tgsis.in_version(conn, "e1"):
        F.delete_feature(conn, "faults", gone)
    conn.commit()
    assert {c.objectkey for c in tgsis.find_conflicts(conn, "e1")} == {str(geoid), str(gone)}
    conn.commit()
    with running_view(db_dsn) as url:
        page.goto(f"{url}/conflicts?version=e1")
        wait_drawn(page)
        rows = page.locator("#regions tbody tr").evaluate_all(
            "rows => rows.map(r => [r.dataset.feature, r.dataset.state])"
        )
        assert [tuple(r) for r in rows] == [(str(geoid), "unsolved")]
        notes = page.locator("#region-notes").text_content()
        assert f"feature {gone}" in notes and "not drawn" in notes, notes


def test_a_solution_recorded_while_the_page_reads_is_seen_whole_or_not_at_all(
    db_dsn: str, conn: psycopg.Connection[Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Another session records a solution between the view's read of the merge and of the solutions.

    The view reads both in one snapshot: the answer is the state before (the
    region unsolved, with that state's regions), the next one the state after.
    """
    import tgsis.view.app as app

    geoid = make_fault(conn)
    move(conn, "e1", geoid, [CONFLICT], (0.0, 0.0, 30.0))
    move(conn, "DEFAULT", geoid, [CONFLICT], (0.0, 0.0, 80.0))
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    region = _region_with(tgsis.object_merge(conn, "e1", geoid), CONFLICT)
    conn.commit()
    real = tgsis.object_merge
    calls: list[int] = []

    def merge_then_resolve(c: psycopg.Connection[Any], version: str, feature_id: int) -> MeshMerge:
        merged = real(c, version, feature_id)
        if not calls:  # the first request only: the other session solves the region meanwhile
            with psycopg.connect(db_dsn) as other:
                tgsis.resolve_region(other, "e1", geoid, region, "base")
                other.commit()
        calls.append(feature_id)
        return merged

    monkeypatch.setattr(app, "object_merge", merge_then_resolve)
    with running_view(db_dsn) as url:
        first, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1")[1])
        second, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1")[1])
    assert [r["solution"] for r in first["regions"] if r["conflict"]] == ["unsolved"]
    assert [r["solution"] for r in second["regions"] if r["conflict"]] == ["base"]
    assert second["regions"][region]["state"] == "solved-base"


# --------------------------------------------------------------------------- models 2 and 3: regions of a slice


def _sliced_conflicts(conn: psycopg.Connection[Any], model: int) -> int:
    """A model-2 surface (instants 1, 2, 3) or a model-3 one (one period starting at 1, geometry instants 1, 2, 3)
    with, between e1 and DEFAULT: at 1 a change of the version's only, at 2 a conflict, at 3 a change of the parent's.
    """
    from tests.test_merge_instants import make_evolving, make_series, move3
    from tests.test_merge_instants import move as move_at

    geoid = make_series(conn) if model == 2 else make_evolving(conn)
    shift = move_at if model == 2 else move3
    shift(conn, "e1", geoid, 1.0, [CHILD_ONLY], (0.0, 0.0, 50.0))
    shift(conn, "e1", geoid, 2.0, [CONFLICT], (0.0, 0.0, 30.0))
    shift(conn, "DEFAULT", geoid, 2.0, [CONFLICT], (0.0, 0.0, 80.0))
    shift(conn, "DEFAULT", geoid, 3.0, [PARENT_ONLY], (0.0, 0.0, 40.0))
    return geoid


@pytest.fixture(scope="module")
def sliced_view(pg: TestServer, template_db: str) -> Iterator[tuple[str, dict[int, int], str]]:
    """A model-2 and a model-3 surface with the regions of :func:`_sliced_conflicts`, each in its database; the views."""
    with (
        pg.database("tgsis_view_sliced2", template_db) as (_, dsn2),
        pg.database("tgsis_view_sliced3", template_db) as (_, dsn3),
    ):
        ids = {}
        for model, dsn in ((2, dsn2), (3, dsn3)):
            with psycopg.connect(dsn) as conn:
                ids[model] = _sliced_conflicts(conn, model)
        with running_view(dsn2) as url2, running_view(dsn3) as url3:
            yield f"{url2} {url3}", ids, f"{dsn2} {dsn3}"


def _slice_of(region: dict[str, Any]) -> float:
    return float(region["slice"]["times"])


@pytest.mark.parametrize("model", [2, 3])
def test_the_endpoint_draws_the_regions_of_the_slice_at_the_views_time(
    sliced_view: tuple[str, dict[int, int], str], model: int
) -> None:
    """Every region of the object is sent, with its slice; those of the slice at t are drawn as model 1's are."""
    urls, ids, dsns = sliced_view
    url, geoid = urls.split()[model - 2], ids[model]
    expected = {1.0: "merges-child", 2.0: "unsolved", 3.0: "merges-parent"}
    for t, moved, dz in ((2.0, CONFLICT, 30.0), (1.0, CHILD_ONLY, 50.0), (3.0, PARENT_ONLY, 0.0)):
        status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1&t={t}")
        assert status == 200, body[:300]
        header, arrays = unpack(body)
        assert header["merges_by_region"] is True, header["reason"]
        regions = header["regions"]
        assert [r["index"] for r in regions] == [0, 1, 2]
        assert {_slice_of(r): r["state"] for r in regions} == expected
        if model == 3:
            assert {r["slice"]["timem"] for r in regions} == {1.0}
        assert header["slice"]["times"] == t and header["t"] == t
        for r in regions:
            assert r["at_t"] is (_slice_of(r) == t)
            if not r["at_t"]:  # listed, not drawn: another slice's mesh is not this one
                assert r["drawn"] == {"vertices": 0, "cells": 0}
        (here,) = [r for r in regions if r["at_t"]]
        assert here["drawn"]["vertices"] == 1 and here["drawn"]["cells"] == 6  # the vertex and its one ring
        # the drawn vertex is the version's at t: the base's shape at that instant, moved by the version's edit
        (v,) = _split(arrays, regions, "vertices")[here["index"]]
        origin = np.asarray(header["origin"])
        position = arrays["positions"].reshape(-1, 3)[v].astype(np.float64) + origin
        shape = curved_surface().vertices[moved] + np.array([0.0, 0.0, 1.0 / 3.0]) * t
        np.testing.assert_allclose(position, shape + [0.0, 0.0, dz], atol=1e-3)
        assert len(arrays["positions"]) == 3 * SIDE * SIDE and len(arrays["changed"]) == SIDE * SIDE
    # no t: the first slice with a conflict
    header, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1")[1])
    assert header["slice"]["times"] == 2.0 and [r["at_t"] for r in header["regions"]] == [False, True, False]
    # a t that is no slice of the merge: the object drawn at t, every region listed, none drawn
    header, arrays = unpack(get(f"{url}/api/conflict/{geoid}?version=e1&t=1.5")[1])
    assert header["slice"] is None and header["t"] == 1.5 and header["merges_by_region"] is True
    assert [r["at_t"] for r in header["regions"]] == [False, False, False]
    assert len(arrays["region_vertices"]) == 0 and header["n_vertices"] == SIDE * SIDE


def test_the_regions_of_a_slice_carry_its_recorded_solutions(pg: TestServer, template_db: str) -> None:
    with pg.database("tgsis_view_sliced_solved", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            geoid = _sliced_conflicts(conn, 2)
            tgsis.find_conflicts(conn, "e1")
            tgsis.resolve_region(conn, "e1", geoid, 1, "base")
            conn.commit()
        with running_view(dsn) as url:
            header, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1&t=2")[1])
    assert header["solutions"] == "recorded"
    assert [(r["index"], r["solution"], r["state"]) for r in header["regions"]] == [
        (0, "automatic", "merges-child"),
        (1, "base", "solved-base"),
        (2, "automatic", "merges-parent"),
    ]


@pytest.mark.parametrize("model", [2, 3])
def test_the_page_draws_the_regions_of_the_instant_chosen_and_names_each_regions_instant(
    sliced_view: tuple[str, dict[int, int], str], page: Any, model: int
) -> None:
    urls, ids, _ = sliced_view
    url, geoid = urls.split()[model - 2], ids[model]
    named = {
        2: {1.0: "instant 1", 2.0: "instant 2", 3.0: "instant 3"},
        3: {t: f"geometry instant {t:g} of the period starting at 1" for t in (1.0, 2.0, 3.0)},
    }[model]
    for t, state in ((2.0, "unsolved"), (1.0, "merges-child"), (3.0, "merges-parent")):
        page.goto(f"{url}/conflicts?version=e1&t={t:g}")
        wait_drawn(page)
        legend = {
            k: _rgb(c)
            for k, c in page.locator("#region-legend [data-state]").evaluate_all(
                "items => items.map(i => [i.dataset.state, getComputedStyle(i.querySelector('.swatch')).backgroundColor])"
            )
        }
        rows = page.locator("#regions tbody tr").evaluate_all(
            "rows => rows.map(r => [r.dataset.region, r.dataset.state, r.dataset.drawn, r.lastElementChild.textContent])"
        )
        # every region of the object is listed with its instant; the instant's own are drawn
        assert sorted(rows) == sorted(
            [
                ["0", "merges-child", str(t == 1.0).lower(), named[1.0]],
                ["1", "unsolved", str(t == 2.0).lower(), named[2.0]],
                ["2", "merges-parent", str(t == 3.0).lower(), named[3.0]],
            ]
        )
        # the time chosen: the instants of the regions offered, this one selected
        assert page.locator("#region-time").input_value() == f"{t:g}"
        assert page.locator("#region-time option").evaluate_all("o => o.map(x => x.value)") == ["1", "2", "3"]
        pixels = canvas_pixels(page)
        boxes = json.loads(page.evaluate("document.body.dataset.regionBoxes"))
        mask = _near(pixels, legend[state])
        assert mask.sum() >= 20, f"t={t}: {mask.sum()} pixels of {state}"
        x0, y0, x1, y1 = boxes[f"{geoid}:{[r[0] for r in rows if r[1] == state][0]}"]
        ys, xs = np.nonzero(mask)
        inside = (xs >= x0 - 3) & (xs <= x1 + 3) & (ys >= y0 - 3) & (ys <= y1 + 3)
        assert inside.mean() > 0.95
        for other in {"unsolved", "merges-child", "merges-parent"} - {state}:  # the other instants' regions: not drawn
            assert _near(pixels, legend[other], 3).sum() == 0, (t, other)
        assert len(boxes) == 1
    # choosing another instant on the page draws its regions
    page.select_option("#region-time", "2")
    page.wait_for_url("**t=2**")
    wait_drawn(page)
    assert page.locator("#regions tbody tr[data-drawn=true]").evaluate_all("r => r.map(x => x.dataset.state)") == [
        "unsolved"
    ]
    ys, xs = np.nonzero(
        _near(
            canvas_pixels(page),
            _rgb(
                page.locator("#region-legend [data-state=unsolved] .swatch").evaluate(
                    "s => getComputedStyle(s).backgroundColor"
                )
            ),
        )
    )
    assert len(xs) >= 20
    # the facts under the pointer name the instant
    pick = int(np.argmin((xs - xs.mean()) ** 2 + (ys - ys.mean()) ** 2))
    canvas = page.locator("#scene").bounding_box()
    page.mouse.move(canvas["x"] + xs[pick] + 0.5, canvas["y"] + ys[pick] + 0.5)
    page.locator("#region-info").wait_for(state="visible")
    assert (
        f"feature {geoid} region 1 at {named[2.0]}: conflict, unsolved" in page.locator("#region-info").text_content()
    )


def test_the_page_quotes_a_version_name_in_the_commands_it_prints(
    regions_view: tuple[str, int, str], page: Any
) -> None:
    """The notes print ``tgsis version conflicts NAME``: NAME as one shell word, as ``shlex.quote`` writes it."""
    import shlex

    url, _, _ = regions_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)
    names = ["e1", "my version", "o'brien", "a$b `c`", "", "x;y", "é"]
    quoted = page.evaluate("names => import('/static/view.js').then(m => names.map(m.shellQuote))", names)
    assert quoted == [shlex.quote(n) for n in names]


def _two_periods(conn: psycopg.Connection[Any]) -> int:
    """A model-3 surface of two topology periods, [1, 2] and [2, 3]: 2 is the first's last geometry instant and the
    second's start, two slices at one time. Between e1 and DEFAULT: a conflict at (1, 2), the version's edit at (2, 2).
    """
    from tests.test_merge_instants import _shape
    from tgsis.temporal import TopologyPeriod

    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    first = TopologyPeriod(np.asarray([1.0, 2.0]), cells, np.stack([_shape(0), _shape(1)]))
    second = TopologyPeriod(np.asarray([2.0, 3.0]), cells, np.stack([_shape(1), _shape(2)]))
    geoid = tgsis.insert_feature(conn, "evolving", tgsis.EvolvingSurface([first, second], name="two periods"))
    tgsis.create_version(conn, "e1")
    conn.commit()
    row = conn.execute(  # the second period's node ids follow the first's
        "SELECT min(nodeid) FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 2", (geoid,)
    ).fetchone()
    conn.commit()
    assert row is not None
    offset = int(row[0])
    for version, timem, node, dz in (
        ("e1", 1.0, CONFLICT, 30.0),
        ("DEFAULT", 1.0, CONFLICT, 80.0),
        ("e1", 2.0, CHILD_ONLY + offset, 50.0),
    ):
        with tgsis.in_version(conn, version):
            conn.execute(
                "UPDATE tgsis.d4dvrtx SET z = z + %s WHERE geoid = %s AND timem = %s AND timet = 2 AND nodeid = %s",
                (dz, geoid, timem, node),
            )
        conn.commit()
    return geoid


@pytest.fixture(scope="module")
def two_periods_view(pg: TestServer, template_db: str) -> Iterator[tuple[str, int]]:
    with pg.database("tgsis_view_two_periods", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            geoid = _two_periods(conn)
        with running_view(dsn) as url:
            yield url, geoid


def test_the_regions_of_a_periods_last_geometry_instant_are_drawn_at_that_period(
    two_periods_view: tuple[str, int],
) -> None:
    """At a period's end the next period starts: ``timem`` chooses the period whose slice at ``t`` is drawn.

    (Was: t = 2 always drew the second period's slice, and the conflict at the first period's last geometry
    instant was listed "drawn when t is theirs" and never drawn.)
    """
    url, geoid = two_periods_view
    conflict = {"times": 2.0, "timem": 1.0}
    for query, drawn in (("&t=2&timem=1", conflict), ("&t=2&timem=2", {"times": 2.0, "timem": 2.0}), ("", conflict)):
        status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1{query}")
        assert status == 200, body[:300]
        header, arrays = unpack(body)
        assert header["slice"] == drawn and header["t"] == 2.0, query
        assert [(r["slice"], r["state"], r["at_t"]) for r in header["regions"]] == [
            (conflict, "unsolved", drawn == conflict),
            ({"times": 2.0, "timem": 2.0}, "merges-child", drawn != conflict),
        ], query
        (here,) = [r for r in header["regions"] if r["at_t"]]
        assert here["drawn"]["vertices"] == 1 and len(arrays["region_vertices"]) == 1
    # t alone: the latest period that has a geometry instant at t (the period starting there), as before
    header, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1&t=2")[1])
    assert header["slice"] == {"times": 2.0, "timem": 2.0}
    # a period with no geometry instant at t: no slice, the object drawn at t
    header, _ = unpack(get(f"{url}/api/conflict/{geoid}?version=e1&t=2.5&timem=1")[1])
    assert header["slice"] is None and not any(r["at_t"] for r in header["regions"])
    status, body, _ = get(f"{url}/api/conflict/{geoid}?version=e1&t=2&timem=x")
    assert status == 400 and b"timem" in body


def test_the_page_offers_each_period_of_a_time_and_draws_the_one_chosen(
    two_periods_view: tuple[str, int], page: Any
) -> None:
    url, _ = two_periods_view
    page.goto(f"{url}/conflicts?version=e1")
    wait_drawn(page)

    def drawn() -> list[str]:
        rows = page.locator("#regions tbody tr[data-drawn=true]")
        return list(rows.evaluate_all("r => r.map(x => x.dataset.state)"))

    options = page.locator("#region-time option").evaluate_all(
        "o => o.map(x => [x.value, x.dataset.timem, x.textContent, x.selected])"
    )
    assert options == [
        ["2", "1", "2 (period starting at 1)", True],
        ["2", "2", "2 (period starting at 2)", False],
    ]
    assert drawn() == ["unsolved"]  # no t: the first slice with a conflict, the first period's last instant
    page.select_option("#region-time", label="2 (period starting at 2)")
    page.wait_for_url("**timem=2**")
    wait_drawn(page)
    assert drawn() == ["merges-child"]
    assert page.locator("#region-time option:checked").text_content() == "2 (period starting at 2)"
    page.select_option("#region-time", label="2 (period starting at 1)")
    page.wait_for_url("**timem=1**")
    wait_drawn(page)
    assert drawn() == ["unsolved"]  # was: t=2 drew the second period's slice, the conflict never
    assert page.locator("#region-time option:checked").text_content() == "2 (period starting at 1)"


def test_a_time_near_an_instant_is_told_apart_from_it_in_the_choice(
    sliced_view: tuple[str, dict[int, int], str], page: Any
) -> None:
    """A t that is no instant, though six digits cannot tell it from one, is offered under its own exact figure.

    (Was: two options "2": the t given, where no region is drawn, selected, and the instant 2 beside it.)
    """
    urls, _, _ = sliced_view
    near = 2.0000000000000004  # the float after 2
    page.goto(f"{urls.split()[0]}/conflicts?version=e1&t={near!r}")
    wait_drawn(page)
    options = page.locator("#region-time option").evaluate_all("o => o.map(x => [x.value, x.textContent, x.selected])")
    assert options == [
        ["1", "1", False],
        ["2", "2", False],
        [repr(near), repr(near), True],
        ["3", "3", False],
    ]
    assert page.locator("#regions tbody tr[data-drawn=true]").count() == 0
