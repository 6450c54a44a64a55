"""The PNG overlay of a conflict (tgsis.pictures.conflict_overlay) shows the solution recorded for each conflicting region.

An unsolved conflict is boxed red and its legend entry says "unsolved"; a
solved one is boxed in the colour of solved conflicts and its legend entry
names the solution (parent, child, base, average, manual). No red is drawn
when every conflict is solved.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest

import tgsis
from tests.merge_data import make_fault, move
from tests.test_view_regions import CHILD_ONLY, CONFLICT, _four_regions, _region_with
from tgsis.db.merging import _state_mesh
from tgsis.errors import InvalidInputError
from tgsis.merge3 import MeshMerge
from tgsis.pictures import OVERLAY_COLOURS, _overlay_legend, conflict_overlay

pytest.importorskip("matplotlib")  # the extra "pictures" (installed by the test extra)

Conn = psycopg.Connection[Any]


def _pixels_near(image: npt.NDArray[Any], colour: str) -> int:
    rgb = np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return int((np.abs(image[:, :, :3] - rgb).max(axis=2) < 0.06).sum())


def _draw(merge: MeshMerge, path: Path, solutions: dict[int, str] | None) -> npt.NDArray[Any]:
    from matplotlib import image as mpimg

    base, parent, child = (_state_mesh(s, "trglid", "fault", {}) for s in (merge.base, merge.parent, merge.child))
    conflict_overlay(merge, base, parent, child, path, title="fault", solutions=solutions)
    return np.asarray(mpimg.imread(path))


def test_the_legend_names_each_conflicts_recorded_solution() -> None:
    merge = _four_regions()
    conflict = _region_with(merge, CONFLICT)
    labels = [label for label, _, _ in _overlay_legend(merge, None)]
    assert f"region {conflict}: conflict, unsolved" in labels
    assert not any("solved with" in label for label in labels)
    for solution in ("parent", "child", "base", "average", "manual"):
        entries = _overlay_legend(merge, {conflict: solution})
        assert (f"region {conflict}: conflict, solved with {solution}", OVERLAY_COLOURS["solved"], "-") in entries
        assert not any("unsolved" in label for label, _, _ in entries)
    with pytest.raises(InvalidInputError, match="'mine'"):
        _overlay_legend(merge, {conflict: "mine"})
    with pytest.raises(InvalidInputError, match="region 99"):
        _overlay_legend(merge, {99: "parent"})


def test_a_solved_conflict_is_boxed_in_the_solved_colour_not_red(tmp_path: Path) -> None:
    merge = _four_regions()
    conflict = _region_with(merge, CONFLICT)
    unsolved = _draw(merge, tmp_path / "unsolved.png", None)
    solved = _draw(merge, tmp_path / "solved.png", {conflict: "average"})
    assert _pixels_near(unsolved, OVERLAY_COLOURS["conflict"]) > 50
    assert _pixels_near(unsolved, OVERLAY_COLOURS["solved"]) == 0
    assert _pixels_near(solved, OVERLAY_COLOURS["solved"]) > 50
    assert _pixels_near(solved, OVERLAY_COLOURS["conflict"]) == 0


def test_the_exported_overlay_shows_the_recorded_solution(conn: Conn, tmp_path: Path) -> None:
    """``tgsis.export_conflict`` draws each conflicting region with the solution recorded for it (tgsis.resolve_region)."""
    from matplotlib import image as mpimg

    geoid = make_fault(conn)
    move(conn, "e1", geoid, [CONFLICT], (0.0, 0.0, 30.0))
    move(conn, "DEFAULT", geoid, [CONFLICT], (0.0, 0.0, 80.0))
    move(conn, "e1", geoid, [CHILD_ONLY], (0.0, 0.0, 10.0))
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    before = np.asarray(mpimg.imread(tgsis.export_conflict(conn, "e1", geoid, tmp_path / "before")[-1]))
    assert _pixels_near(before, OVERLAY_COLOURS["conflict"]) > 50  # recorded, but unsolved: red
    assert _pixels_near(before, OVERLAY_COLOURS["solved"]) == 0
    region = _region_with(tgsis.object_merge(conn, "e1", geoid), CONFLICT)
    tgsis.resolve_region(conn, "e1", geoid, region, "average")
    conn.commit()
    after = np.asarray(mpimg.imread(tgsis.export_conflict(conn, "e1", geoid, tmp_path / "after")[-1]))
    assert _pixels_near(after, OVERLAY_COLOURS["solved"]) > 50
    assert _pixels_near(after, OVERLAY_COLOURS["conflict"]) == 0
