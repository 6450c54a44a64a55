"""The sample applications run end to end from ``tgsis demo NAME`` (issue 18).

Each scenario runs at its small size against the test server (``--dsn``; it
makes its own database there), and what it prints, stores and draws is
checked: the SQL it shows gives the answer it shows when run again, SQL and
Python snapshots agree, and the pictures, animation and ParaView series are
real files of their kinds.
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from PIL import Image
from psycopg.conninfo import make_conninfo

from tgsis import formats
from tgsis.cli import build_parser, main
from tgsis.db.versions import list_versions
from tgsis.formats.pvd import read_pvd
from tgsis.merge3 import MeshState


def test_the_scenarios_are_listed(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--list"]) == 0
    names = [line.split("\t")[0] for line in capsys.readouterr().out.splitlines()]
    assert names == [
        "scenario",
        "saltdome",
        "synsed",
        "river",
        "interpretations",
        "mine",
        "knowledge",
        "merge",
        "cfm",
    ]  # header first
    assert main(["demo", "--list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["scenarios"]
    assert [s["name"] for s in listed] == names[1:] and all(s["summary"] for s in listed)
    assert main(["demo", "--json"]) == 1
    assert "--json and --no-header go with --list" in capsys.readouterr().err


def test_an_unknown_scenario_is_refused_naming_the_scenarios(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", "host=/nonexistent", "demo", "volcano"]) == 1
    err = capsys.readouterr().err
    assert (
        "no scenario 'volcano'" in err
        and "cfm, interpretations, knowledge, merge, mine, river, saltdome, synsed" in err
    )


def _printed_sql(out: str) -> list[tuple[str, str]]:
    """(statement, answer) pairs the report printed."""
    lines = out.splitlines()
    return [
        (lines[i].strip().rstrip(";"), lines[i + 1].strip().removeprefix("-> "))
        for i in range(len(lines) - 1)
        if lines[i].strip().startswith(("SELECT ", "WITH ")) and lines[i + 1].strip().startswith("->")
    ]


def _replays(db_dsn: str, scenario: str, out: str, count: int) -> None:
    """The SQL the report shows runs as printed, in the scenario's database, and gives the answer shown."""
    asked = _printed_sql(out)
    assert len(asked) == count
    with psycopg.connect(make_conninfo(db_dsn, dbname=f"tgsis_demo_{scenario}")) as conn:
        for statement, answer in asked:
            values = answer.split(": ", 1)[1]
            rows = conn.execute(statement).fetchall()
            assert "; ".join(", ".join(str(v) for v in row) for row in rows) == values, statement


def test_saltdome(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "salt"
    assert main(["--dsn", db_dsn, "demo", "saltdome", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert out.count("equal to SQL to the bit: yes") == 2
    assert "flat at t = 0 (231 vertices, a grid), a dome at t = 1 (194 vertices, Delaunay)" in out
    _replays(db_dsn, "saltdome", out, 2)
    tops = [float(m) for m in re.findall(r"-> vertices, top_m, lowest_m: \d+, (-?[\d.]+)", out)]
    assert -2500 < tops[1] < tops[0] < -1000  # risen more by 2/3 than by 1/2
    # pictures, animation and series
    for name in ("saltdome_known_shapes.png", "saltdome_t2_3.png", "saltdome_t1_2.png"):
        with Image.open(folder / name) as picture:
            assert picture.format == "PNG" and picture.size == (800, 600)
    with Image.open(folder / "saltdome.gif") as movie:
        assert movie.format == "GIF" and movie.n_frames == 11  # type: ignore[attr-defined]  # PIL: only multi-frame formats
    frames = read_pvd(folder / "saltdome.pvd")
    assert len(frames) == 11 and frames[0][0] == 0.0 and frames[-1][0] == 1.0
    assert "summary: interpolation_error_m" in out


def test_interpretations(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "interp"
    assert main(["--dsn", db_dsn, "demo", "interpretations", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    # the design's figure (its 7.3), which its own steps give under the hand-out rules (versioning.md)
    figure = "DEFAULT {0, 1, 3, 4}; version1 based on 0 {2}; version2 based on 3 {5}"
    assert f"   revisions in the design (7.3): {figure}" in out
    assert f"   revisions tgsis handed out:   {figure}" in out
    assert "revision 0: model 1 (seismic picks)" in out and "version1 (based on revision 0), revision 2: model 2" in out
    assert (
        "DEFAULT, revision 1: the restored model 1" in out
        and "version2 (based on revision 3), revision 5: model 3" in out
    )
    # the design's question over models (named sets of objects) and the objects' type: the fault is first in model 3
    assert "-> model, version, revision: model 3, version2, 5" in out
    dilated = re.search(r"-> model, version, max_dilatancy: (.*)", out)
    assert dilated is not None
    assert [tuple(p.split(", ")[:2]) for p in dilated.group(1).split("; ")] == [
        ("model 2", "version1"),
        ("model 3", "version2"),
    ]
    _replays(db_dsn, "interpretations", out, 2)
    for label in ("1", "2", "3"):
        with Image.open(folder / f"interpretations_model{label}.png") as picture:
            assert picture.format == "PNG"


def test_synsed(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "synsed"
    assert main(["--dsn", db_dsn, "demo", "synsed", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    # C, D and E each grow from the horizon beneath during the interval before they are first known
    assert (
        "horizon A 3 period(s), horizon B 3 period(s), horizon C 3 period(s), horizon D 2 period(s), "
        "horizon E 1 period(s)"
    ) in out
    assert "C grows from B over [1, 2], D grows from C over [2, 3], E grows from D over [3, 4]" in out
    # at t = 2.5: the fault and the horizons deposited by then (D is being deposited), equal in SQL and Python
    assert (
        "-> surface, vertices, triangles: fault F, 15, 16; horizon A, 70, 96; horizon B, 70, 96; "
        "horizon C, 70, 96; horizon D, 70, 96"
    ) in out
    assert "equal to SQL to the bit: yes" in out
    # throw = 60 m/Myr since deposition (A at 0, B at 1, C at 2): older horizons carry more
    assert "-> horizon, throw_m: horizon A, 150.0; horizon B, 90.0; horizon C, 30.0; horizon D, 0.0" in out
    _replays(db_dsn, "synsed", out, 2)
    for name in ("synsed_t1.png", "synsed_t2_5.png", "synsed_t4.png"):
        with Image.open(folder / name) as picture:
            assert picture.format == "PNG"


def test_river(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "river"
    assert main(["--dsn", db_dsn, "demo", "river", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    # the pinch-outs attached to the basement stayed on it at every geometry instant
    strayed = re.search(r"at most ([0-9.e+-]+) m off it at any instant", out)
    assert strayed is not None and float(strayed.group(1)) < 1e-9
    assert "unit 3 12 vertex-intervals" in out  # the later shape as the source too
    assert "unit 2 deposited over [0, 1], unit 3 deposited over [2, 3]" in out
    assert "-> surface, vertices, triangles: basement, 606, 1000; unit 1, 150, 240; unit 2, 150, 240\n" in out
    assert (
        "-> surface, vertices, triangles: basement, 606, 1000; unit 1, 150, 240; unit 2, 150, 240; unit 3, 150, 240"
    ) in out  # unit 3 growing at t = 2.5
    assert "equal to SQL to the bit: yes" in out
    # which unit lies on which: unit 3 reaches unit 1 between t = 3 and 4
    assert "-> unit, lies_on: unit 1, basement; unit 2, basement, unit 1; unit 3, basement, unit 2" in out
    assert "-> unit, lies_on: unit 1, basement; unit 2, basement, unit 1; unit 3, basement, unit 1, unit 2" in out
    _replays(db_dsn, "river", out, 4)
    for name in ("river_t1_5.png", "river_t2_5.png", "river_t3.png", "river_t4.png"):
        with Image.open(folder / name) as picture:
            assert picture.format == "PNG"


def test_knowledge(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "knowledge"
    assert main(["--dsn", db_dsn, "demo", "knowledge", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    # the box over x, y and knowledge finds the anticline's history, not the one 5 km east
    assert "-> feature, horizon: 1, top anticline" in out
    crest = re.search(r"each campaign found the crest deeper: (.*) m", out)
    assert crest is not None
    depths = [float(v) for v in crest.group(1).split(" > ")]
    assert len(depths) == 4 and depths == sorted(depths, reverse=True)
    assert "Euler characteristic 1 (a disk times an interval: 1; Python says 1)" in out
    assert out.count("the picked points: yes") == 4
    _replays(db_dsn, "knowledge", out, 3)
    with Image.open(folder / "knowledge_interpretations.png") as picture:
        assert picture.format == "PNG"
    frames = read_pvd(folder / "knowledge.pvd")
    assert [t for t, _ in frames] == [2019.0, 2021.0, 2023.0, 2025.0]


def test_mine(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "mine"
    assert main(["--dsn", db_dsn, "demo", "mine", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "survey_2021 (child of survey_2019), believed 2021-05-01 .. 2023-06-01" in out
    assert "survey_2023 (child of survey_2021), believed 2023-06-01 .. still" in out
    # on 2022-01-15 the 2021 model was believed: 14 holes, the ore top and F1 (F2 came in 2023)
    assert "-> version, objects, boreholes, surfaces: survey_2021, 16, 14, F1, ore top" in out
    assert "-> models: geotechnical model, resource model" in out  # F1 is in both
    stored = re.search(
        r"-> version, stored, seen: survey_2019, (\d+), (\d+); survey_2021, (\d+), (\d+); "
        r"survey_2023, (\d+), (\d+)",
        out,
    )
    assert stored is not None
    first, seen_first, second, seen_second, third, seen_third = (int(v) for v in stored.groups())
    assert first == seen_first
    with psycopg.connect(make_conninfo(db_dsn, dbname="tgsis_demo_mine")) as conn:  # the scenario's own database
        chunked = conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
    if chunked:
        # a revision stores only the chunks it changes, each whole (docs/storage.md, "Versioning of chunks"):
        # the unchanged objects' chunks are not stored again, the unchanged rows of a changed chunk are
        assert second < seen_second and third < seen_third, (second, seen_second, third, seen_third)
    else:
        assert second < seen_second / 2 and third < seen_third / 2  # unchanged rows not stored again
    _replays(db_dsn, "mine", out, 5)
    # believed on a date: in each period and on its bounds ([from, to): a survey's day belongs to the new model)
    with psycopg.connect(make_conninfo(db_dsn, dbname="tgsis_demo_mine")) as conn:
        for day, expected in (
            ("2019-02-28 23:59:59+00", None),
            ("2019-03-01 00:00:00+00", "survey_2019"),
            ("2020-07-01 12:00:00+00", "survey_2019"),
            ("2021-04-30 23:59:59.999+00", "survey_2019"),
            ("2021-05-01 00:00:00+00", "survey_2021"),
            ("2023-05-31 23:59:59+00", "survey_2021"),
            ("2023-06-01 00:00:00+00", "survey_2023"),
            ("2031-01-01 00:00:00+00", "survey_2023"),
        ):
            assert conn.execute("SELECT tgsis.version_believed_at(%s::timestamptz)", (day,)).fetchone() == (
                expected,
            ), day
    with Image.open(folder / "mine_ore_top.png") as picture:
        assert picture.format == "PNG"


def _fault_state(conn: psycopg.Connection[Any], geoid: int, version: str, revision: int | None) -> MeshState:
    """The fault as ``version`` (at ``revision``) holds it, read through tgsis.rows_at as a psql user would."""
    vertices = conn.execute(
        "SELECT vrtxid, x, y, z FROM tgsis.rows_at(NULL::tgsis.vrtx, %s, %s) WHERE geoid = %s ORDER BY vrtxid",
        (version, revision, geoid),
    ).fetchall()
    cells = conn.execute(
        "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.rows_at(NULL::tgsis.trgl, %s, %s) "
        "WHERE geoid = %s ORDER BY trglid",
        (version, revision, geoid),
    ).fetchall()
    return MeshState(
        3,
        np.array([r[0] for r in vertices]),
        np.array([r[1:] for r in vertices], dtype=np.float64),
        np.array([r[0] for r in cells]),
        np.array([r[1:] for r in cells]),
        name=f"{version}@{revision}",
    )


def _moved(state: MeshState, base: MeshState) -> npt.NDArray[np.int64]:
    """Ids of the vertices whose coordinates differ from the base's (same ids, same cells on both)."""
    assert np.array_equal(state.vertex_ids, base.vertex_ids) and np.array_equal(state.cells, base.cells)
    return state.vertex_ids[np.any(state.vertices != base.vertices, axis=1)]


def _triangles_on(base: MeshState, moved: npt.NDArray[np.int64]) -> int:
    """The triangles with a moved vertex: a region's one-ring margin (docs/merge.md)."""
    return int(np.isin(base.cells, moved).any(axis=1).sum())


def _region_words(base: MeshState, moved: npt.NDArray[np.int64]) -> str:
    """How the report counts a region of moved vertices: the vertices and the triangles on them."""
    return f"{len(moved)} vertices, {_triangles_on(base, moved)} triangles"


def _metres(state: MeshState, base: MeshState, ids: npt.NDArray[np.int64]) -> float:
    """The largest distance a vertex of ``ids`` moved from the base, in whole metres."""
    at = np.searchsorted(base.vertex_ids, ids)
    return float(round(np.linalg.norm(state.vertices[at] - base.vertices[at], axis=1).max()))


def _largest(state: MeshState, base: MeshState, ids: npt.NDArray[np.int64]) -> str:
    return f"{_metres(state, base, ids):.0f} m"


def test_merge(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "merge"
    assert main(["--dsn", db_dsn, "demo", "merge", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m (feature 1, 716 vertices, 1271 triangles)" in out
    with psycopg.connect(make_conninfo(db_dsn, dbname="tgsis_demo_merge")) as conn:
        versions = {v.name: v for v in list_versions(conn)}
        base = _fault_state(conn, 1, "DEFAULT", versions["DEFAULT"].saved["release_5.3"])
        assert base.n_vertices == 716 and base.n_cells == 1271
        ann, bob, cat = (
            _fault_state(conn, 1, name, versions[name].saved[f"{name}_edit"])
            for name in ("north_tip", "south_tip", "north_review")
        )
        both = _fault_state(conn, 1, "DEFAULT", versions["DEFAULT"].saved["both_tips"])
        final = _fault_state(conn, 1, "DEFAULT", None)
    a, b, c = _moved(ann, base), _moved(bob, base), _moved(cat, base)
    # the edits as stated: ann's and bob's at the two ends, cat's over ann's
    assert len(a) > 20 and len(b) > 20 and len(np.intersect1d(a, c)) > 20
    assert not len(np.intersect1d(a, b)) and not len(np.intersect1d(b, c))
    for name, state, moved in (("north_tip", ann, a), ("south_tip", bob, b), ("north_review", cat, c)):
        assert (
            f"({name}) " in out
            and f": {len(moved)} vertices moved (up to {_largest(state, base, moved)}), {2 * len(moved) + 1} rows written"
            in out
        )

    # the merge of south_tip: ann's region (parent) and bob's (child), disjoint, merged by themselves
    assert f"changed by parent, merges by itself; {_region_words(base, a)} (parent moved {len(a)}, up to " in out
    assert f"changed by child, merges by itself; {_region_words(base, b)} (parent moved 0, up to 0 m; child" in out
    # ... and DEFAULT then holds both edits bit for bit, the rest and every triangle as the base
    assert np.array_equal(both.vertex_ids, base.vertex_ids) and np.array_equal(both.cells, base.cells)
    assert np.array_equal(both.cell_ids, base.cell_ids)
    expected = base.vertices.copy()
    for side, moved in ((ann, a), (bob, b)):
        at = np.searchsorted(base.vertex_ids, moved)
        expected[at] = side.vertices[at]
    assert both.vertices.tobytes() == expected.tobytes()
    assert "bit for bit, every other vertex and every triangle as in release 5.3: yes" in out
    # ... writing into DEFAULT only bob's rows (a closed and a new one per moved vertex, and the fault's box),
    # never ann's again, which DEFAULT holds already; in chunks, the chunk versions holding them (each chunk
    # written whole: docs/storage.md, "What differs from rows")
    into_south_tip = 2 * len(a) + 1
    with psycopg.connect(make_conninfo(db_dsn, dbname="tgsis_demo_merge")) as conn:
        row = conn.execute(
            "SELECT tgsis.stored_in_chunks('vrtx'), chunksize FROM tgsis.model_tables WHERE tablename = 'vrtx'"
        ).fetchone()
    assert row is not None
    chunked, chunksize = bool(row[0]), int(row[1])
    # in chunks: each vertex chunk bob's moves are in, closed and written anew (chunk versions), and the fault's
    # box (its geometry row closed and written anew: rows), each unit counted apart (MergeResult)
    into_default = (
        f"{2 * len(np.unique(b // chunksize))} chunk versions and 2 rows" if chunked else f"{2 * len(b) + 2} rows"
    )
    assert (
        f"{into_south_tip} rows written into south_tip (the merged fault, by id: ann's moves), then "
        f"{into_default} into DEFAULT (only what it did not hold: bob's moves, "
    ) in out

    # the merge of north_review: one conflict region, exactly ann's and cat's moved vertices and the triangles
    # on them; bob's region (now the parent's) merges by itself
    union = np.union1d(a, c)
    assert (
        f"changed by both, a CONFLICT; {_region_words(base, union)} "
        f"(parent moved {len(a)}, up to {_largest(ann, base, a)}; child moved {len(c)}, up to {_largest(cat, base, c)})"
    ) in out
    assert f"changed by parent, merges by itself; {_region_words(base, b)}" in out.split("5. north_review")[1]
    assert out.count("a CONFLICT") == 1
    # ... and what a psql user reads of them in tgsis.conflict_regions once the conflict is solved by average
    assert (
        "=> region, changed_by, solution, vertices, triangles, parent_m, child_m: "
        f"0, both, average, {len(union)}, {_triangles_on(base, union)}, {_metres(ann, base, a)}, "
        f"{_metres(cat, base, c)}; 1, parent, automatic, {len(b)}, {_triangles_on(base, b)}, "
        f"{_metres(bob, base, b)}, 0.0"
    ) in out

    # solved by average: every vertex of the region between ann's and cat's position, bob's edit and the rest kept
    assert np.array_equal(final.vertex_ids, base.vertex_ids) and np.array_equal(final.cells, base.cells)
    inside = np.isin(final.vertex_ids, union)
    assert final.vertices[~inside].tobytes() == both.vertices[~inside].tobytes()
    p, q, r = ann.vertices[inside], cat.vertices[inside], final.vertices[inside]
    span = q - p
    t = np.einsum("ij,ij->i", r - p, span) / np.einsum("ij,ij->i", span, span)
    assert np.all(t > 0.0) and np.all(t < 1.0)
    off_segment = np.linalg.norm(r - (p + t[:, None] * span), axis=1)
    assert off_segment.max() <= 1e-9 * np.linalg.norm(span, axis=1).max()
    assert r.tobytes() == (0.5 * p + 0.5 * q).tobytes()  # halfway, the rule of docs/merge.md, to the bit
    assert "-> position_as_in, vertices: none (the average), 108; release 5.3, 499; south_tip (bob), 109" in out
    assert "-> triangles, not_as_in_release_5_3: 1271, 0" in out

    _replays(db_dsn, "merge", out, 3)
    after = out.split("8. steps 3 to 6 from the command line")[1].splitlines()[1:]
    commands = [line.strip() for line in after if line.startswith("   tgsis ")]
    assert len(commands) == 7 and "tgsis version resolve north_review 1 average --region 0" in commands
    for command in commands:  # the commands shown are the command line's
        build_parser().parse_args(shlex.split(command)[1:])
    overlay = folder / "1_CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m_overlay.png"
    for picture_file in (overlay, folder / "merge_both_tips.png", folder / "merge_resolved.png"):
        with Image.open(picture_file) as picture:
            assert picture.format == "PNG"
    for exported in ("base", "parent", "child"):
        assert formats.read_one(folder / f"1_CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m_{exported}.ts").n_vertices == 716


def test_merge_without_the_cfm_data_runs_on_a_synthetic_fault(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A trimmed install (no data/cfm): the same story on the stand-in fault, saying so, with the same outcome."""
    from tgsis.scenarios import run_scenario

    monkeypatch.setenv("TGSIS_DEMO_DATA", str(tmp_path / "no such folder"))
    lines: list[str] = []
    result = run_scenario("merge", db_dsn, out=lines.append, folder=tmp_path / "out")
    out = "\n".join(lines)
    assert "data: synthetic faults (no CFM data found)" in out and "middle_fault (feature 1, 360 vertices" in out
    assert result.figures["both_edits_kept"] is True and result.figures["conflict_region_exact"] is True
    low, high = result.figures["average_between"]
    assert 0.0 < low <= high < 1.0
    assert (tmp_path / "out" / "merge_resolved.png").is_file()
