"""Scenario ``merge``: three geologists edit one real fault in three versions; the merges keep every edit.

A fault of the SCEC Community Fault Model (release 5.3, GOCAD TSurf from
``data/cfm``; a synthetic stand-in when that folder is missing) is stored in
DEFAULT in the versioned class ``faults``. Small: the smallest fault of the
release (the Oceanic fault, 716 vertices); large: the largest. Its "northern"
end is the one of larger northing along strike (the report names it by the
compass). Three geologists start from that same state, each in a version of
their own:

1. **ann** (``north_tip``) maps the trace further beyond the northern tip:
   the vertices within 12 % of the fault's length of that end are stretched
   outwards along strike, the tip by 2 % of the length, smoothly tapering
   (a half cosine) to nothing at the zone's inner edge;
2. **bob** (``south_tip``) puts the southern end's base deeper (relocated
   seismicity): the vertices within 15 % of the length of the southern end
   slide down dip (in the fault's mean plane) in proportion to their depth,
   1,000 m at the fault's base and not at all at its top, with the same taper
   along strike;
3. **cat** (``north_review``) re-picks the northern tip on a new seismic line:
   the vertices within 17 % of the length of that end are bent 600 m sideways
   (horizontal, normal to strike), tapered likewise — an edit overlapping
   ann's.

Each checks the fault out of their version, edits it in Python and checks it
in by difference (only the moved vertices are written). Then:

- ann's version is merged into DEFAULT (DEFAULT had not changed the fault);
- bob's edit and ann's (now in DEFAULT) are two disjoint regions of one mesh:
  the merge of ``south_tip`` keeps both, automatically; the merged fault holds
  each edit bit for bit (checked in Python and asked in SQL);
- cat's edit and ann's overlap: one conflict region (``tgsis.find_conflicts``:
  ids, box, largest displacements), bob's region merges by itself; the
  conflict is drawn (``tgsis.export_conflict``: the three states as GOCAD
  files and the overlay PNG), solved by ``average`` (``tgsis.resolve_region``:
  each vertex of the region halfway between ann's and cat's position, the
  rule of docs/merge.md for two sides of one meshing; what it discards of
  each side is said first) and merged.

The state the three started from is kept as the named revision
``release_5.3`` of DEFAULT, the state after the first two merges as
``both_tips`` (a merge moves a version's base, so these are what the SQL
compares with). The SQL a psql user runs to see the result through the
versioned views is printed with its answers; then the same steps as
``tgsis`` commands. Pictures: the overlay of the conflict and the merged
fault coloured by how far each vertex moved from release 5.3, the regions
boxed with their solutions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

import tgsis
from tgsis import pictures
from tgsis._cfm import CfmFault, load_releases
from tgsis.db.checkin import checkin, checkout
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.versions import (
    ConflictRegion,
    create_version,
    enable_feature_versioning,
    in_version,
    list_versions,
    save_revision,
)
from tgsis.mesh import Surface
from tgsis.scenarios._context import Context
from tgsis.scenarios._fault_edits import FaultFrame, bend_tip, deepen_tip, lengthen_tip

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: ann: the tip stretched outwards by this fraction of the fault's length, over a zone of this fraction of it
LENGTHEN = (0.02, 0.12)
#: bob: metres down dip at the fault's base, over a zone of this fraction of the length
DEEPEN = (1000.0, 0.15)
#: cat: metres sideways at the tip, over a zone of this fraction of the length
BEND = (600.0, 0.17)


@dataclass(frozen=True)
class Edit:
    """One geologist's edit of the fault in their version, as checked in."""

    geologist: str
    version: str
    what: str
    moved: IntArray  # vertex ids moved
    vertices: FloatArray  # (n, 3) the whole fault after the edit, rows in vertex-id order
    largest: float  # the largest distance a vertex moved (m)
    rows: int  # rows the check-in wrote
    revision: int  # the revision the edit was saved as


def _pick(faults: list[CfmFault], size: str) -> CfmFault:
    """The smallest fault (small) or the largest (large) of the release."""
    by_size = sorted(faults, key=lambda f: (f.mesh.n_vertices, f.name))
    return by_size[0] if size == "small" else by_size[-1]


def _vertices(conn: Any, geoid: int, version: str, revision: int | None = None) -> tuple[IntArray, FloatArray]:
    """The fault's vertex ids and coordinates as ``version`` (at ``revision``) holds them, by id."""
    with conn.transaction():
        rows = conn.execute(
            "SELECT vrtxid, x, y, z FROM tgsis.rows_at(NULL::tgsis.vrtx, %s, %s) WHERE geoid = %s ORDER BY vrtxid",
            (version, revision, geoid),
        ).fetchall()
    ids = np.array([r[0] for r in rows], dtype=np.int64)
    return ids, np.array([r[1:] for r in rows], dtype=np.float64).reshape(-1, 3)


def _triangles(conn: Any, geoid: int, version: str, revision: int | None = None) -> IntArray:
    """(m, 4): trglid and vertex ids of the fault's triangles as ``version`` (at ``revision``) holds them."""
    with conn.transaction():
        rows = conn.execute(
            "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.rows_at(NULL::tgsis.trgl, %s, %s) "
            "WHERE geoid = %s ORDER BY trglid",
            (version, revision, geoid),
        ).fetchall()
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


Change = Callable[[FloatArray, FaultFrame], tuple[FloatArray, npt.NDArray[np.bool_]]]


def _edit(context: Context, geoid: int, geologist: str, version: str, what: str, change: Change) -> Edit:
    """Check the fault out of ``version``, move its vertices by ``change(vertices, frame)``, check it in, save."""
    conn = context.conn
    with in_version(conn, version):
        checked_out = checkout(conn, geoid)
        edited = checked_out.mesh.copy()
        moved_to, moved = change(edited.vertices, FaultFrame.of(edited.vertices))
        edited.vertices[:] = moved_to
        result = checkin(conn, checked_out, edited)
        revision = save_revision(conn, f"{version}_edit")
        conn.commit()
    order = np.argsort(checked_out.base.vertex_ids)
    return Edit(
        geologist,
        version,
        what,
        np.sort(checked_out.base.vertex_ids[moved]),
        moved_to[order],
        float(np.linalg.norm(moved_to - checked_out.mesh.vertices, axis=1).max()),
        result.save.rows_written,
        revision,
    )


def _copied(result: tgsis.MergeResult) -> str:
    """What the SQL merge wrote into the parent, each unit apart (chunk versions only where model 1 is in chunks)."""
    if result.chunk_versions_copied:
        return f"{result.chunk_versions_copied} chunk versions and {result.rows_copied} rows"
    return f"{result.rows_copied} rows"


def _ids_text(ids: IntArray, shown: int = 8) -> str:
    """Ids as ascending runs, ``"3-17, 40, 52-60"``; after ``shown`` runs, ``"..."`` and the count."""
    ids = np.asarray(ids, dtype=np.int64)
    if not len(ids):
        return "none"
    breaks = np.flatnonzero(np.diff(ids) != 1) + 1
    runs = [(int(r[0]), int(r[-1])) for r in np.split(ids, breaks)]
    text = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs[:shown])
    return text + (f", ... ({len(ids)} in all)" if len(runs) > shown else "")


def _region_lines(region: ConflictRegion) -> list[str]:
    """What a region is: who changed it, its ids, box and largest displacements (as tgsis.find_conflicts has it)."""
    x0, y0, z0, x1, y1, z1 = np.asarray(region.bbox) if region.bbox is not None else [np.nan] * 6
    return [
        f"region {region.region}: changed by {region.changed_by}, "
        f"{'a CONFLICT' if region.conflict else 'merges by itself'}; "
        f"{len(region.vertex_ids)} vertices, {len(region.cell_ids)} triangles "
        f"(parent moved {len(region.parent_vertex_ids)}, up to {region.parent_displacement:.0f} m; "
        f"child moved {len(region.child_vertex_ids)}, up to {region.child_displacement:.0f} m); "
        f"box x {x0:.0f}..{x1:.0f}, y {y0:.0f}..{y1:.0f}, z {z0:.0f}..{z1:.0f}",
        f"  vertex ids {_ids_text(region.vertex_ids)}",
    ]


def _list_regions(context: Context, version: str) -> list[ConflictRegion]:
    """``tgsis.find_conflicts`` of ``version``, its regions printed; the regions of the (one) conflicting fault."""
    conflicts = tgsis.find_conflicts(context.conn, version)
    regions: list[ConflictRegion] = []
    for conflict in conflicts:
        context.out(
            f"   tgsis.find_conflicts: {conflict.objectclass} {conflict.objectkey} changed on both sides "
            f"({', '.join(conflict.conflicttype)}), {len(conflict.regions)} region(s)"
            + (f"; not by region: {conflict.region_refusal}" if conflict.region_refusal else "")
        )
        for region in conflict.regions:
            for line in _region_lines(region):
                context.out(f"     {line}")
        regions.extend(conflict.regions)
    context.figure(f"regions_of_{version}", [(r.changed_by, r.conflict) for r in regions])
    return regions


def _ask_now(context: Context, question: str, query: sql.Composed) -> None:
    """Like :meth:`Context.ask`, for an answer of this moment (``=>``: a later step changes it)."""
    with context.conn.transaction():
        cursor = context.conn.execute(query)
        rows = cursor.fetchall()
        names = [d.name for d in cursor.description or []]
    context.out(f"   {question}")
    context.out(f"     {query.as_string(context.conn)};")
    context.out(f"     => {', '.join(names)}: " + "; ".join(", ".join(str(v) for v in row) for row in rows))


def _names(paths: list[Path]) -> str:
    return ", ".join(p.name for p in paths)


def _rows_at(version: str, revision: int | None, table: str = "vrtx") -> sql.Composed:
    """``tgsis.rows_at(NULL::tgsis.<table>, version, revision)``: the rows as that version saw them then."""
    return sql.SQL("tgsis.rows_at(NULL::tgsis.{}, {}, {})").format(
        sql.Identifier(table), sql.Literal(version), sql.Literal(revision)
    )


def _same_bits(a: FloatArray, b: FloatArray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def _provenance_sql(
    geoid: int, sources: Sequence[tuple[str, str, int | None]], merged: sql.Composable, otherwise: str = "none of them"
) -> sql.Composed:
    """Per vertex of the merged fault, the first source whose position it has (bit-equal in SQL: float8 ``=``)."""
    joins = sql.SQL(" ").join(
        sql.SQL("LEFT JOIN tgsis.rows_at(NULL::tgsis.vrtx, {}, {}) {} USING (geoid, vrtxid)").format(
            sql.Literal(version), sql.Literal(revision), sql.Identifier(f"s{i}")
        )
        for i, (_, version, revision) in enumerate(sources)
    )
    cases = sql.SQL(" ").join(
        sql.SQL("WHEN (m.x, m.y, m.z) = ({s}.x, {s}.y, {s}.z) THEN {label}").format(
            s=sql.Identifier(f"s{i}"), label=sql.Literal(label)
        )
        for i, (label, _, _) in enumerate(sources)
    )
    return sql.SQL(
        "SELECT CASE {cases} ELSE {otherwise} END AS position_as_in, count(*) AS vertices "
        "FROM {merged} m {joins} WHERE m.geoid = {geoid} GROUP BY 1 ORDER BY 1"
    ).format(cases=cases, merged=merged, joins=joins, geoid=sql.Literal(geoid), otherwise=sql.Literal(otherwise))


def _exactly(region: ConflictRegion, parent: Edit, child: Edit, triangles: IntArray) -> bool:
    """Whether a conflict region holds exactly the two sides' moved vertices and the triangles on them."""
    union = np.union1d(parent.moved, child.moved)
    on = triangles[np.isin(triangles[:, 1:], union).any(axis=1), 0]
    return bool(
        np.array_equal(np.asarray(region.parent_vertex_ids), parent.moved)
        and np.array_equal(np.asarray(region.child_vertex_ids), child.moved)
        and np.array_equal(np.asarray(region.vertex_ids), union)
        and np.array_equal(np.asarray(region.cell_ids), on)
    )


def _draw(
    context: Context,
    geoid: int,
    base_ids: IntArray,
    base_xyz: FloatArray,
    regions: list[ConflictRegion],
    solutions: dict[int, str],
    file: str,
    title: str,
) -> Path:
    """DEFAULT's fault now, coloured by how far each vertex lies from its place in release 5.3, regions boxed."""
    ids, xyz = _vertices(context.conn, geoid, "DEFAULT")
    frame = FaultFrame.of(base_xyz)
    triangles = _triangles(context.conn, geoid, "DEFAULT")[:, 1:]
    moved = np.full(len(ids), np.nan)
    at = np.searchsorted(base_ids, ids).clip(0, max(len(base_ids) - 1, 0))
    known = base_ids[at] == ids
    moved[known] = np.linalg.norm(xyz[known] - base_xyz[at[known]], axis=1)
    boxes = [
        (
            np.asarray(r.bbox).reshape(2, 3),
            f"region {r.region}: {r.changed_by}, {solutions.get(r.region, r.solution)}",
            "tab:red" if r.conflict else "tab:green",
        )
        for r in regions
        if r.bbox is not None
    ]
    return pictures.scene(
        [Surface(xyz, np.searchsorted(ids, triangles), name="merged")],
        context.folder / file,
        title=title,
        colour=[np.nan_to_num(moved)],
        colour_label="distance from release 5.3 (m)",
        exaggeration=2.0,
        boxes=boxes,
        view=(25.0, float(np.degrees(np.arctan2(frame.normal[1], frame.normal[0])))),  # facing the fault
    )


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    source, releases = load_releases()
    fault = _pick(releases[0], context.size)
    frame = FaultFrame.of(fault.mesh.vertices)
    length = float(np.ptp(frame.along))
    north, south = frame.end_name(1), frame.end_name(-1)
    create_feature_class(conn, "faults", "SURFACE", srs=26911, description="fault surfaces, UTM zone 11 metres, z up")
    enable_feature_versioning(conn)
    geoid = insert_feature(conn, "faults", fault.mesh, drop_extra_properties=True)
    conn.commit()
    out(f"data: {source}")
    out(
        f"1. DEFAULT: {fault.name} (feature {geoid}, {fault.mesh.n_vertices} vertices, "
        f"{fault.mesh.n_cells} triangles), {length / 1000:.1f} km along strike from its {south}ern to its "
        f"{north}ern end, dipping {np.degrees(np.arccos(frame.normal[2])):.0f} degrees"
    )
    base_revision = save_revision(conn, "release_5.3")  # a merge moves a version's base: keep this one by name
    for version, geologist in (("north_tip", "ann"), ("south_tip", "bob"), ("north_review", "cat")):
        create_version(conn, version, description=f"{geologist}'s edit of {fault.name}")
    conn.commit()
    based = {v.initrevision for v in list_versions(conn) if v.name in ("north_tip", "south_tip", "north_review")}
    out(
        f"   saved as revision {base_revision} (release_5.3); versions north_tip (ann), south_tip (bob) and "
        f"north_review (cat) made from it one after the other (based on revisions "
        f"{', '.join(str(r) for r in sorted(r for r in based if r is not None))} of DEFAULT: the same fault)"
    )

    stretch, stretch_zone = LENGTHEN[0] * length, LENGTHEN[1] * length
    slide, slide_zone = DEEPEN[0], DEEPEN[1] * length
    bend, bend_zone = BEND[0], BEND[1] * length
    edits = [
        _edit(
            context,
            geoid,
            "ann",
            "north_tip",
            f"maps the trace beyond the {north}ern tip: the {stretch_zone / 1000:.1f} km next to it stretched "
            f"along strike, the tip {stretch:.0f} m further {north}",
            lambda v, f: lengthen_tip(v, f, 1, stretch, stretch_zone),
        ),
        _edit(
            context,
            geoid,
            "bob",
            "south_tip",
            f"puts the {south}ern end's base deeper: the {slide_zone / 1000:.1f} km next to the tip slide down dip "
            f"in proportion to depth ({slide:.0f} m at the base, none at the top)",
            lambda v, f: deepen_tip(v, f, -1, slide, slide_zone),
        ),
        _edit(
            context,
            geoid,
            "cat",
            "north_review",
            f"re-picks the {north}ern tip: the {bend_zone / 1000:.1f} km next to it bent {bend:.0f} m "
            f"{frame.side_name(1)}, horizontally",
            lambda v, f: bend_tip(v, f, 1, bend, bend_zone),
        ),
    ]
    ann, bob, cat = edits
    out("2. the three edits, each checked out of its version and checked in by difference:")
    for e in edits:
        out(
            f"   {e.geologist} ({e.version}) {e.what}: {len(e.moved)} vertices moved (up to {e.largest:.0f} m), "
            f"{e.rows} rows written, "
            f"saved as revision {e.revision}"
        )
    context.figure("vertices_moved", {e.version: len(e.moved) for e in edits})
    base_ids, base_xyz = _vertices(conn, geoid, "DEFAULT", base_revision)
    base_triangles = _triangles(conn, geoid, "DEFAULT", base_revision)

    # what merge_version writes into the parent, each unit apart (MergeResult): rows, and where model 1 is stored
    # in chunks the chunk versions of the vertex and triangle tables (each chunk a changed vertex or triangle is in,
    # written whole: docs/storage.md, "What differs from rows"); the rows a merge by region writes into the version
    # are rows on both storages
    chunked = conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
    held = (
        "the chunks holding them, each written whole, and the fault's box"
        if chunked
        else "a row closed and one written per vertex, and the fault's box"
    )

    # 3. ann merges first: DEFAULT had not changed the fault
    north_tip = tgsis.merge_version(conn, "north_tip")
    out(f"3. north_tip merged into DEFAULT (which had not changed the fault): {_copied(north_tip)} written")

    # 4. bob's edit against ann's, now in DEFAULT: two disjoint regions of one mesh, merged by themselves
    out("4. south_tip: DEFAULT and south_tip both changed the fault since release_5.3")
    regions = _list_regions(context, "south_tip")
    result = tgsis.merge_version(conn, "south_tip")
    for merged_object in result.objects:
        out(
            f"   merged by region ({merged_object.how}, {merged_object.regions} regions): "
            f"{merged_object.rows_written} rows written into south_tip (the merged fault, by id: ann's moves), then "
            f"{_copied(result)} into DEFAULT (only what it did not hold: bob's "
            f"moves, {held}), for {len(ann.moved) + len(bob.moved)} vertices moved (the whole fault written "
            f"again: {2 * fault.mesh.n_vertices + fault.mesh.n_cells} rows)"
        )
    context.figure("south_tip_rows", result.rows_by_region + result.rows_copied)
    context.figure("south_tip_chunk_versions", result.chunk_versions_copied)
    both = save_revision(conn, "both_tips")
    conn.commit()
    ids, merged = _vertices(conn, geoid, "DEFAULT")
    expected = base_xyz.copy()
    for e in (ann, bob):
        at = np.searchsorted(base_ids, e.moved)
        expected[at] = e.vertices[at]
    kept = bool(
        np.array_equal(ids, base_ids)
        and _same_bits(merged, expected)
        and np.array_equal(_triangles(conn, geoid, "DEFAULT"), base_triangles)
    )
    out(
        f"   DEFAULT (saved as revision {both}, both_tips) holds ann's {len(ann.moved)} and bob's {len(bob.moved)} "
        f"moved vertices bit for bit, every other vertex and every triangle as in release 5.3: {'yes' if kept else 'NO'}"
    )
    context.figure("both_edits_kept", kept)
    sources = [
        ("release 5.3", "DEFAULT", base_revision),
        ("north_tip (ann)", "north_tip", ann.revision),
        ("south_tip (bob)", "south_tip", bob.revision),
    ]
    context.ask(
        "in psql: where each vertex of DEFAULT's fault at revision both_tips comes from",
        _provenance_sql(geoid, sources, _rows_at("DEFAULT", both)),
    )
    context.wrote(
        _draw(
            context,
            geoid,
            base_ids,
            base_xyz,
            regions,
            {},
            "merge_both_tips.png",
            f"{fault.name}\nDEFAULT after north_tip and south_tip",
        )
    )

    # 5. cat's edit overlaps ann's: one conflict region; bob's, now DEFAULT's, merges by itself
    out("5. north_review: cat's tip against DEFAULT's (ann's), and bob's end, both changed since release_5.3")
    regions = _list_regions(context, "north_review")
    clash = [r for r in regions if r.conflict]
    exact = len(clash) == 1 and _exactly(clash[0], ann, cat, base_triangles)
    out(
        "   the conflict region is exactly ann's and cat's moved vertices and the triangles on them: "
        f"{'yes' if exact else 'NO'}"
    )
    context.figure("conflict_region_exact", exact)
    written = tgsis.export_conflict(conn, "north_review", geoid, context.folder, overwrite=True)
    context.wrote(written)
    out(f"   to look at it in one's own tool (tgsis version conflicts north_review --export DIR): {_names(written)}")

    # 6. solved by average, merged
    for region in clash:
        solved = tgsis.resolve_region(conn, "north_review", geoid, region.region, "average")
        out(
            f"6. region {region.region} solved by average (each vertex halfway between ann's and cat's), "
            "which discards of each side's edit there, as tgsis.resolve_region counts it:"
        )
        for d in solved.discards:
            out(
                f"   {'ann' if d.side == 'parent' else 'cat'}'s ({d.side}): {d.vertices} vertices, {d.cells} cells "
                f"not as that side has them; the largest move away from its position {d.max_displacement:.0f} m"
            )
    _ask_now(
        context,
        "in psql, before the merge: the regions of north_review and their solutions",
        sql.SQL(
            "SELECT region, changed_by, solution, cardinality(vertex_ids) AS vertices, "
            "cardinality(cell_ids) AS triangles, round(parent_displacement) AS parent_m, "
            "round(child_displacement) AS child_m FROM tgsis.conflict_regions "
            "WHERE versionid = (SELECT versionid FROM tgsis.versions WHERE name = {}) ORDER BY region"
        ).format(sql.Literal("north_review")),
    )
    result = tgsis.merge_version(conn, "north_review")
    out(
        f"   north_review merged: {result.rows_by_region} rows written into north_review by region"
        + "".join(f" ({m.how})" for m in result.objects)
        + f", then {_copied(result)} into DEFAULT"
    )
    _, final = _vertices(conn, geoid, "DEFAULT")
    _, both_xyz = _vertices(conn, geoid, "DEFAULT", both)
    inside = np.isin(base_ids, np.union1d(ann.moved, cat.moved))
    kept = _same_bits(final[~inside], both_xyz[~inside])
    span = cat.vertices[inside] - ann.vertices[inside]
    t = np.einsum("ij,ij->i", final[inside] - ann.vertices[inside], span) / np.einsum("ij,ij->i", span, span)
    out(
        "   outside the region the fault is as after the first two merges (bob's end bit for bit): "
        f"{'yes' if kept else 'NO'}; the region's {int(inside.sum())} vertices lie {t.min():.3f} to {t.max():.3f} "
        "of the way from ann's position to cat's"
    )
    context.figure("rest_kept", kept)
    context.figure("average_between", (round(float(t.min()), 6), round(float(t.max()), 6)))
    context.ask(
        "in psql, in DEFAULT (the session's version): where each vertex of the fault comes from now",
        _provenance_sql(
            geoid,
            [*sources, ("north_review (cat)", "north_review", cat.revision)],
            sql.SQL("tgsis.vrtx"),
            otherwise="none (the average)",
        ),
    )
    context.ask(
        "in psql: the fault's triangles in DEFAULT now, and how many are not as in release 5.3",
        sql.SQL(
            "SELECT count(m.trglid) AS triangles, count(*) FILTER (WHERE (m.vrtxid1, m.vrtxid2, m.vrtxid3) "
            "IS DISTINCT FROM (b.vrtxid1, b.vrtxid2, b.vrtxid3)) AS not_as_in_release_5_3 "
            "FROM (SELECT * FROM tgsis.trgl WHERE geoid = {g}) m "
            "FULL JOIN (SELECT * FROM {base} WHERE geoid = {g}) b USING (trglid)"
        ).format(g=sql.Literal(geoid), base=_rows_at("DEFAULT", base_revision, "trgl")),
    )
    context.wrote(
        _draw(
            context,
            geoid,
            base_ids,
            base_xyz,
            regions,
            {r.region: "average" for r in clash},
            "merge_resolved.png",
            f"{fault.name}\nDEFAULT after the three merges",
        )
    )
    out(f"7. pictures: {_names([p for p in context.files if p.suffix == '.png'])}")
    out("8. steps 3 to 6 from the command line (tgsis --dsn DSN ..., DSN that of the database tgsis_demo_merge):")
    for command in (
        "version merge north_tip",
        "version conflicts south_tip --regions",
        "version merge south_tip",
        "version conflicts north_review --regions --json",
        "version conflicts north_review --export DIR",
        *(f"version resolve north_review {geoid} average --region {r.region}" for r in clash),
        "version merge north_review",
    ):
        out(f"   tgsis {command}")
