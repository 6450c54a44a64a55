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
   slide down dip, by up to 1,000 m at the fault's base and not at all at its
   top, with the same taper along strike;
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
  the morphological average of ann's and cat's tip, attached to the rest)
  and merged.

The SQL a psql user runs to see the result through the versioned views is
printed with its answers. Pictures: the overlay of the conflict and the
merged fault coloured by how far each vertex moved from release 5.3, the
regions boxed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

import tgsis
from tgsis import pictures
from tgsis._cfm import CfmFault, load_releases
from tgsis.db.checkin import checkin, checkout
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.versions import create_version, enable_feature_versioning, in_version, list_versions, save_revision
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


def _edit(context: Context, geoid: int, geologist: str, version: str, what: str, change: Any) -> Edit:
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


def _region_line(region: Any) -> str:
    """What a region of a merge is: who changed it, its ids, box and largest displacements."""
    (x0, y0, z0), (x1, y1, z1) = np.asarray(region.bounds)
    return (
        f"region {region.index}: changed by {region.sides}, "
        f"{'a CONFLICT' if region.conflict else 'merges by itself'}; "
        f"{len(region.vertex_ids)} vertices, {len(region.cell_ids)} triangles "
        f"(parent moved {len(region.parent_vertex_ids)}, up to {region.parent_displacement:.0f} m; "
        f"child moved {len(region.child_vertex_ids)}, up to {region.child_displacement:.0f} m); "
        f"box x {x0:.0f}..{x1:.0f}, y {y0:.0f}..{y1:.0f}, z {z0:.0f}..{z1:.0f}"
    )


def _same_bits(a: FloatArray, b: FloatArray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def _provenance_sql(geoid: int, sources: list[tuple[str, str, int | None]], merged: sql.Composable) -> sql.Composed:
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
        "SELECT CASE {cases} ELSE 'none of them' END AS position_as_in, count(*) AS vertices "
        "FROM {merged} m {joins} WHERE m.geoid = {geoid} GROUP BY 1 ORDER BY 1"
    ).format(cases=cases, merged=merged, joins=joins, geoid=sql.Literal(geoid))


def _exactly(region: Any, parent: Edit, child: Edit, triangles: IntArray) -> bool:
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
    regions: Any,
    file: str,
    title: str,
) -> Any:
    """DEFAULT's fault now, coloured by how far each vertex lies from its place in release 5.3, regions boxed."""
    ids, xyz = _vertices(context.conn, geoid, "DEFAULT")
    triangles = _triangles(context.conn, geoid, "DEFAULT")[:, 1:]
    moved = np.full(len(ids), np.nan)
    at = np.searchsorted(base_ids, ids).clip(0, max(len(base_ids) - 1, 0))
    known = base_ids[at] == ids
    moved[known] = np.linalg.norm(xyz[known] - base_xyz[at[known]], axis=1)
    boxes = [
        (
            np.asarray(r.bounds),
            f"region {r.index}: {r.sides}{' (conflict)' if r.conflict else ''}",
            "tab:red" if r.conflict else "tab:green",
        )
        for r in regions
    ]
    return pictures.scene(
        [Surface(xyz, np.searchsorted(ids, triangles), name="merged")],
        context.folder / file,
        title=title,
        colour=[np.nan_to_num(moved)],
        colour_label="distance from release 5.3 (m)",
        exaggeration=2.0,
        boxes=boxes,
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
    for version, geologist in (("north_tip", "ann"), ("south_tip", "bob"), ("north_review", "cat")):
        create_version(conn, version, description=f"{geologist}'s edit of {fault.name}")
    conn.commit()
    base_revision = next(v.initrevision for v in list_versions(conn) if v.name == "north_tip")
    out(f"   versions north_tip (ann), south_tip (bob), north_review (cat), all based on revision {base_revision}")

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

    # 3. ann merges first: DEFAULT had not changed the fault
    rows = tgsis.merge_version(conn, "north_tip")
    conn.commit()
    out(f"3. north_tip merged into DEFAULT (which had not changed the fault): {rows} rows written")

    # 4. bob's edit against ann's, now in DEFAULT: two disjoint regions of one mesh
    out(f"4. south_tip against DEFAULT: both changed the fault since revision {base_revision}; its regions:")
    preview = tgsis.object_merge(conn, "south_tip", geoid)
    for region in preview.regions:
        out(f"   {_region_line(region)}")
    context.figure("regions_of_south_tip", [(r.sides, r.conflict) for r in preview.regions])
    rows = tgsis.merge_version(conn, "south_tip")
    conn.commit()
    changed = len(ann.moved) + len(bob.moved)
    out(
        f"   merged by region: {rows} rows written ({changed} vertices changed on the two sides; "
        f"a whole fault is {2 * fault.mesh.n_vertices + fault.mesh.n_cells} rows)"
    )
    both = save_revision(conn, "both_tips")
    conn.commit()
    ids, merged = _vertices(conn, geoid, "DEFAULT")
    expected = base_xyz.copy()
    for e in (ann, bob):
        expected[np.searchsorted(base_ids, e.moved)] = e.vertices[np.searchsorted(base_ids, e.moved)]
    kept = bool(
        np.array_equal(ids, base_ids)
        and _same_bits(merged, expected)
        and np.array_equal(_triangles(conn, geoid, "DEFAULT"), base_triangles)
    )
    out(
        f"   DEFAULT (saved as revision {both}) holds ann's {len(ann.moved)} and bob's {len(bob.moved)} vertices "
        f"bit for bit, every other vertex and every triangle as in release 5.3: {'yes' if kept else 'NO'}"
    )
    context.figure("both_edits_kept", kept)
    provenance = [
        ("release 5.3", "DEFAULT", base_revision),
        ("north_tip (ann)", "north_tip", ann.revision),
        ("south_tip (bob)", "south_tip", bob.revision),
    ]
    context.ask(
        "in psql: where each vertex of the merged fault comes from (revision both_tips of DEFAULT)",
        _provenance_sql(
            geoid, provenance, sql.SQL("tgsis.rows_at(NULL::tgsis.vrtx, 'DEFAULT', {})").format(sql.Literal(both))
        ),
    )
    context.wrote(
        _draw(
            context,
            geoid,
            base_ids,
            base_xyz,
            preview.regions,
            "merge_both_tips.png",
            f"{fault.name}\nDEFAULT after merging north_tip and south_tip",
        )
    )

    # 5. cat's edit overlaps ann's: one conflict region; bob's, now DEFAULT's, merges by itself
    out("5. north_review against DEFAULT (both tips merged): cat's tip over ann's")
    conflicts = tgsis.find_conflicts(conn, "north_review")
    conn.commit()
    regions = [r for c in conflicts for r in c.regions]
    for region in regions:
        out(f"   {_region_line(region)}")
    context.figure("regions_of_north_review", [(r.sides, r.conflict) for r in regions])
    clash = [r for r in regions if r.conflict]
    exact = len(clash) == 1 and _exactly(clash[0], ann, cat, base_triangles)
    out(
        "   the conflict region is exactly ann's and cat's moved vertices and the triangles on them: "
        f"{'yes' if exact else 'NO'}"
    )
    context.figure("conflict_region_exact", exact)
    written = tgsis.export_conflict(conn, "north_review", geoid, context.folder, overwrite=True)
    context.wrote(written)
    out(f"   the three states (GOCAD), the regions and the overlay: {', '.join(p.name for p in written)}")

    # 6. solved by average, merged
    for region in clash:
        solved = tgsis.resolve_region(conn, "north_review", geoid, region.index, "average")
        conn.commit()
        out(f"6. region {region.index} solved by average: {solved}")
    rows = tgsis.merge_version(conn, "north_review")
    conn.commit()
    out(f"   north_review merged: {rows} rows written")
    _, final = _vertices(conn, geoid, "DEFAULT")
    ids_now, both_xyz = _vertices(conn, geoid, "DEFAULT", both)
    inside = np.isin(base_ids, np.union1d(ann.moved, cat.moved))
    kept = bool(_same_bits(final[~inside], both_xyz[~inside]))
    span = cat.vertices[inside] - ann.vertices[inside]
    t = np.einsum("ij,ij->i", final[inside] - ann.vertices[inside], span) / np.einsum("ij,ij->i", span, span)
    out(
        f"   outside the region the fault is as after the first merges (bob's tip bit for bit): {'yes' if kept else 'NO'}; "
        f"the {int(inside.sum())} vertices of the region lie from {t.min():.2f} to {t.max():.2f} of the way "
        "from ann's position to cat's"
    )
    context.figure("average_between", (float(t.min()), float(t.max())))
    sources = [
        *provenance,
        ("north_review (cat)", "north_review", cat.revision),
        ("DEFAULT after the first merges", "DEFAULT", both),
    ]
    context.ask(
        "in psql, in DEFAULT (the session's version): where each vertex of the fault comes from now",
        _provenance_sql(geoid, sources, sql.SQL("tgsis.vrtx")),
    )
    context.wrote(
        _draw(
            context,
            geoid,
            base_ids,
            base_xyz,
            regions,
            "merge_resolved.png",
            f"{fault.name}\nDEFAULT after merging north_review (its tip the average of ann's and cat's)",
        )
    )
