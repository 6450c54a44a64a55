"""Scenario ``interpretations``: one horizon, several models, in versions and revisions, in the design's order.

The specification's fourth sample application, after the source design's
walk-through (its section 7.3), step by step in the design's order so that
the revision numbers are the design's own:

1. DEFAULT, revision 0: model 1, the horizon from seismic picks;
2. ``version1`` from DEFAULT (based on revision 0; DEFAULT then works in 1,
   ``version1`` in 2): model 2, an alternative interpretation, in revision 2;
3. DEFAULT, revision 1: the restored (unfolded) model 1, saved as a named
   revision (``tgsis.save_revision``: revision 1 is frozen, DEFAULT works in 3);
4. DEFAULT, revision 3: drill-hole picks added;
5. ``version2`` from DEFAULT (based on revision 3; DEFAULT then works in 4,
   ``version2`` in 5): model 3, where a thrust fault cuts the horizon into
   two blocks (a topology change), in revision 5.

So DEFAULT holds {0, 1, 3, 4}, version1 (based on 0) {2}, version2 (based
on 3) {5} -- the design's figure; the report prints its numbers beside the
ones tgsis handed out. Each model is a named set of objects (the design's
model table: ``tgsis.create_model``), whose objects have a type (their
feature class: horizons, restored, faults, picks).

A restored state is a feature of its own (``<horizon> restored``) with the
same vertices as the horizon it restores, carrying per vertex the
**dilatancy**: the relative change of the area of the vertex's one-ring (its
triangles) from the model to its restored state, ``|A_restored - A| / A``.
Restoring here flattens the horizon onto its mean depth, so a tighter fold
gives a larger dilatancy. The cross-version questions, in SQL over every
revision of every version (``tgsis.rows_at``): in which model does the fault
first appear (the design's question: the first model, by revision, with an
object of type fault), and in which models is the dilatancy above a
threshold.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from psycopg import sql

from tgsis import pictures
from tgsis.db.checkin import save_feature
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.modelsets import create_model
from tgsis.db.versions import create_version, enable_feature_versioning, in_version, save_revision
from tgsis.mesh import PointSet, Surface
from tgsis.scenarios._context import Context

#: The horizon's extent (m), mean depth (m, elevation) and the threshold of the dilatancy question.
EXTENT = (6000.0, 3000.0)
DEPTH = -1800.0
THRESHOLD = 0.05


def _grid(nx: int, ny: int, x0: float, x1: float) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(0, EXTENT[1], ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return np.stack([u.ravel(), v.ravel()], 1), np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def horizon(amplitude: float, n: int, *, blocks: bool = False, name: str = "horizon H") -> Surface:
    """A folded horizon (an anticline of ``amplitude`` metres); with ``blocks`` cut by a thrust into two blocks."""
    parts = [(0.0, 0.45 * EXTENT[0], 0.0), (0.55 * EXTENT[0], EXTENT[0], 250.0)] if blocks else [(0.0, EXTENT[0], 0.0)]
    vertices, triangles, offset = [], [], 0
    for x0, x1, lift in parts:
        xy, tri = _grid(max(3, int(n * (x1 - x0) / EXTENT[0])), max(3, n // 2), x0, x1)
        z = DEPTH + lift + amplitude * np.cos(np.pi * (xy[:, 0] / EXTENT[0] - 0.5)) ** 2
        vertices.append(np.column_stack([xy, z]))
        triangles.append(tri + offset)
        offset += len(xy)
    return Surface(np.concatenate(vertices), np.concatenate(triangles), name=name)


def ring_areas(surface: Surface) -> np.ndarray:
    """(n,) float64: the area of each vertex's one-ring (the triangles around it)."""
    v, tri = surface.vertices, surface.cells
    area = 0.5 * np.linalg.norm(np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]]), axis=1)
    rings = np.zeros(len(v))
    for corner in range(3):
        np.add.at(rings, tri[:, corner], area)
    return rings


def restored(model: Surface) -> Surface:
    """The model flattened onto its mean depth, with the dilatancy of each vertex as a vertex property."""
    flat = model.vertices.copy()
    flat[:, 2] = model.vertices[:, 2].mean()
    state = Surface(flat, model.cells, name=f"{model.name} restored")
    before, after = ring_areas(model), ring_areas(state)
    return Surface(flat, model.cells, name=state.name, vertex_properties={"dilatancy": np.abs(after - before) / before})


def fault(n: int) -> Surface:
    """The thrust fault between the blocks: a plane dipping west, through the gap."""
    xy, tri = _grid(4, max(3, n // 2), 0.0, 1.0)
    depth = np.linspace(DEPTH - 600, DEPTH + 900, 4)[np.rint(xy[:, 0] * 3).astype(int)]
    x = 0.45 * EXTENT[0] + 0.1 * EXTENT[0] * (depth - (DEPTH - 600)) / 1500
    return Surface(np.column_stack([x, xy[:, 1], depth]), tri, name="thrust T")


def drill_holes() -> PointSet:
    """Horizon picks in five drill holes."""
    xy = np.array([[1000, 800], [2500, 1500], [3100, 2200], [4200, 900], [5400, 2500]], dtype=float)
    return PointSet(
        np.column_stack([xy, DEPTH + 150.0 * np.cos(np.pi * (xy[:, 0] / EXTENT[0] - 0.5)) ** 2]),
        name="drill-hole picks",
    )


#: The design's figure (section 7.3): each version's base revision and the revisions it holds.
DESIGN = {"DEFAULT": (None, [0, 1, 3, 4]), "version1": (0, [2]), "version2": (3, [5])}


def revisions_of(conn: Any) -> dict[str, tuple[int | None, list[int]]]:
    """Each version's base revision and the revisions it holds, as tgsis handed them out."""
    rows = conn.execute(
        "SELECT v.name, v.initrevision, array_agg(r.revision ORDER BY r.revision) "
        "FROM tgsis.versions v JOIN tgsis.revisions r USING (versionid) "
        "GROUP BY v.name, v.initrevision"
    ).fetchall()
    return {name: (base, list(revisions)) for name, base, revisions in rows}


def _figure_line(revisions: dict[str, tuple[int | None, list[int]]]) -> str:
    return "; ".join(
        f"{name}{'' if base is None else f' based on {base}'} {{{', '.join(map(str, held))}}}"
        for name, (base, held) in ((n, revisions.get(n, (None, []))) for n in DESIGN)
    )


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    n = 41 if context.size == "large" else 13
    create_feature_class(conn, "horizons", "SURFACE")
    create_feature_class(
        conn,
        "restored",
        "SURFACE",
        cell_properties={"dilatancy": "float8"},
        alignment="VERTEX",
        description="restored (unfolded) states of horizons, with their dilatancy",
    )
    create_feature_class(conn, "faults", "SURFACE")
    create_feature_class(conn, "picks", "MULTIPOINT")
    enable_feature_versioning(conn)
    conn.commit()

    # 1. DEFAULT {0}: model 1 from seismic picks, in revision 0
    model_1 = horizon(400.0, n)
    h = insert_feature(conn, "horizons", model_1)
    create_model(conn, "model 1", [h], description="interpretation of seismic picks")
    conn.commit()
    out(f"1. DEFAULT, revision 0: model 1 (seismic picks): horizon, feature {h}")
    # 2. version1 from DEFAULT: based on 0; DEFAULT gets 1, version1 gets 2
    create_version(conn, "version1", description="an alternative interpretation")
    with in_version(conn, "version1"):
        model_2 = horizon(1200.0, n)
        save_feature(conn, "horizons", h, model_2)
        r2 = insert_feature(conn, "restored", restored(model_2))
        create_model(conn, "model 2", [h, r2], description="alternative interpretation, with its restored state")
        conn.commit()
    out(
        f"2. version1 (based on revision 0), revision 2: model 2, an alternative interpretation, with its restored "
        f"state (feature {r2})"
    )
    # 3. DEFAULT, revision 1: the restored model 1, saved as a named revision; DEFAULT works in 3
    r1 = insert_feature(conn, "restored", restored(model_1))
    create_model(conn, "model 1 restored", [r1], description="restored (unfolded) model 1")
    conn.commit()
    saved = save_revision(conn, "restored_model_1")
    conn.commit()
    out(
        f"3. DEFAULT, revision {saved}: the restored model 1 (feature {r1}), saved as the named revision "
        f"'restored_model_1'"
    )
    # 4. DEFAULT, revision 3: drill-hole picks
    picks = insert_feature(conn, "picks", drill_holes())
    create_model(conn, "drill holes", [h, picks], description="model 1 with the drill-hole picks")
    conn.commit()
    out(f"4. DEFAULT, revision 3: drill-hole picks (feature {picks})")
    # 5. version2 from DEFAULT: based on 3; DEFAULT gets 4, version2 gets 5
    create_version(conn, "version2", description="the drill holes show a thrust")
    with in_version(conn, "version2"):
        model_3 = horizon(800.0, n, blocks=True)
        save_feature(conn, "horizons", h, model_3)
        t = insert_feature(conn, "faults", fault(n))
        r3 = insert_feature(conn, "restored", restored(model_3))
        create_model(conn, "model 3", [h, t, r3, picks], description="the horizon cut by a thrust into two blocks")
        conn.commit()
    out(
        f"5. version2 (based on revision 3), revision 5: model 3, a thrust (feature {t}) cuts the horizon into two "
        f"blocks ({model_3.n_vertices} vertices); restored (feature {r3})"
    )
    got = revisions_of(conn)
    out("   revisions in the design (7.3): " + _figure_line(DESIGN))
    out("   revisions tgsis handed out:   " + _figure_line(got))
    context.figure(
        "revisions_as_the_design", all(got.get(name) == (base, list(held)) for name, (base, held) in DESIGN.items())
    )

    # the cross-version questions, over every revision of every version
    first = context.ask(
        "in which model does the fault first appear?",
        sql.SQL(
            "SELECT m.name AS model, v.name AS version, r.revision "
            "FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid), "
            "LATERAL tgsis.rows_at(NULL::tgsis.model, v.name, r.revision) m "
            "WHERE EXISTS (SELECT FROM tgsis.rows_at(NULL::tgsis.model_object, v.name, r.revision) mo "
            "JOIN tgsis.rows_at(NULL::public.faults, v.name, r.revision) f ON f._geoid = mo.geoid "
            "WHERE mo.modelid = m.modelid) "
            "ORDER BY r.revision, m.name LIMIT 1"
        ),
    )
    context.figure("fault_first_in", first[0][0] if first else None)
    above = context.ask(
        f"in which models is the dilatancy above {THRESHOLD}?",
        sql.SQL(
            "SELECT m.name AS model, v.name AS version, round(max(p.dilatancy)::numeric, 3) AS max_dilatancy "
            "FROM tgsis.versions v, LATERAL tgsis.rows_at(NULL::tgsis.model, v.name) m "
            "JOIN tgsis.rows_at(NULL::tgsis.model_object, v.name) mo ON mo.modelid = m.modelid "
            "JOIN tgsis.rows_at(NULL::public.restored_cellpros, v.name) p ON p._geoid = mo.geoid "
            "GROUP BY m.name, v.name HAVING max(p.dilatancy) > {} ORDER BY v.name, m.name"
        ).format(sql.Literal(THRESHOLD)),
    )
    context.figure("dilatancy_above_in", [row[0] for row in above])

    out("5. pictures")
    for label, model, restored_state in (
        ("1", model_1, restored(model_1)),
        ("2", model_2, restored(model_2)),
        ("3", model_3, restored(model_3)),
    ):
        surfaces: list[Surface] = [model, restored_state] + ([fault(n)] if label == "3" else [])
        colours = [None, restored_state.vertex_properties["dilatancy"]] + ([None] if label == "3" else [])
        context.wrote(
            pictures.scene(
                surfaces,
                context.folder / f"interpretations_model{label}.png",
                colour=colours,
                colour_label="dilatancy (relative ring-area change)",
                title=f"model {label} and its restored state",
            )
        )
    out(f"   {', '.join(p.name for p in context.files)}")
