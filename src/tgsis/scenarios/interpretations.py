"""Scenario ``interpretations``: one horizon, several models, in versions and named revisions.

The specification's fourth sample application, after the source design's
walk-through. Each model is a named revision (``tgsis.save_revision``):

- model 1.1, the horizon from seismic picks, in DEFAULT;
- ``version1``: an alternative interpretation, model 2.1, and its restored
  (unfolded) state, model 2.2;
- model 1.2 in DEFAULT: the restored state of model 1.1;
- drill-hole picks added in DEFAULT;
- ``version2``, from DEFAULT after the drill holes: a thrust fault cuts the
  horizon into two blocks (a topology change), model 3.1, and its restored
  state, model 3.2.

A restored state is a feature of its own (``<horizon> restored``) with the
same vertices as the horizon it restores, carrying per vertex the
**dilatancy**: the relative change of the area of the vertex's one-ring (its
triangles) from the model to its restored state, ``|A_restored - A| / A``.
Restoring here flattens the horizon onto its mean depth, so a tighter fold
gives a larger dilatancy. Revision numbers follow the hand-out rules of the
specification (versioning.md: a new version takes its parent's working
revision as its base, the parent a new revision, then the child; a save
freezes the working revision and starts the next); the report prints them
next to the rules' numbers. The cross-version questions, in SQL over every
named revision: in which model does the fault appear first, and in which
models is the dilatancy above a threshold.
"""

from __future__ import annotations

import numpy as np
from psycopg import sql

from tgsis import pictures
from tgsis.db.checkin import save_feature
from tgsis.db.features import create_feature_class, insert_feature
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
    return PointSet(np.column_stack([xy, DEPTH + 150.0 * np.cos(np.pi * (xy[:, 0] / EXTENT[0] - 0.5)) ** 2]),
                    name="drill-hole picks")


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    n = 41 if context.size == "large" else 13
    create_feature_class(conn, "horizons", "SURFACE")
    create_feature_class(conn, "restored", "SURFACE", cell_properties={"dilatancy": "float8"}, alignment="VERTEX",
                         description="restored (unfolded) states of horizons, with their dilatancy")
    create_feature_class(conn, "faults", "SURFACE")
    create_feature_class(conn, "picks", "MULTIPOINT")
    enable_feature_versioning(conn)
    conn.commit()
    expected = {}   # model -> revision, by the hand-out rules (versioning.md)
    got = {}

    def save(model: str) -> None:
        got[model] = save_revision(conn, model)
        conn.commit()

    # DEFAULT starts with {0}; model 1.1 is written in revision 0 and saved: DEFAULT works in 1
    model_11 = horizon(400.0, n)
    h = insert_feature(conn, "horizons", model_11)
    save("model1.1")
    expected["model1.1"] = 0
    out(f"1. model 1.1 (seismic picks): feature {h} in DEFAULT, saved as revision {got['model1.1']}")
    # version1: base = DEFAULT's working revision 1; DEFAULT gets 2, version1 gets 3
    create_version(conn, "version1", description="an alternative interpretation")
    with in_version(conn, "version1"):
        model_21 = horizon(1200.0, n)
        save_feature(conn, "horizons", h, model_21)
        save("model2.1")                                             # revision 3; version1 works in 4
        r21 = insert_feature(conn, "restored", restored(model_21))
        save("model2.2")                                             # revision 4; version1 works in 5
    expected.update({"model2.1": 3, "model2.2": 4})
    out(f"2. version1: model 2.1 saved as revision {got['model2.1']}, its restored state (feature {r21}) "
        f"as model 2.2, revision {got['model2.2']}")
    # back in DEFAULT (working revision 2): the restored model 1.1
    r11 = insert_feature(conn, "restored", restored(model_11))
    save("model1.2")                                                 # revision 2; DEFAULT works in 6
    expected["model1.2"] = 2
    picks = insert_feature(conn, "picks", drill_holes())
    conn.commit()
    out(f"3. DEFAULT: model 1.2, the restored model 1.1 (feature {r11}), saved as revision {got['model1.2']}; "
        f"drill-hole picks added (feature {picks}) in revision 6")
    # version2 from DEFAULT: base 6; DEFAULT gets 7, version2 gets 8
    create_version(conn, "version2", description="the drill holes show a thrust")
    with in_version(conn, "version2"):
        model_31 = horizon(800.0, n, blocks=True)
        save_feature(conn, "horizons", h, model_31)
        t = insert_feature(conn, "faults", fault(n))
        save("model3.1")                                             # revision 8
        r31 = insert_feature(conn, "restored", restored(model_31))
        save("model3.2")                                             # revision 9
    expected.update({"model3.1": 8, "model3.2": 9})
    out(f"4. version2: a thrust (feature {t}) cuts the horizon into two blocks ({model_31.n_vertices} vertices), "
        f"model 3.1 saved as revision {got['model3.1']}; restored (feature {r31}) as model 3.2, revision {got['model3.2']}")
    out("   revisions by the hand-out rules: " + ", ".join(f"{m} {r}" for m, r in expected.items()))
    out("   revisions tgsis handed out:      " + ", ".join(f"{m} {got[m]}" for m in expected))
    context.figure("revisions_as_the_rules_say", got == expected)

    # the cross-version questions: every named revision is a model
    first = context.ask("in which model does the fault appear first?", sql.SQL(
        "SELECT r.name AS model, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) "
        "WHERE r.name IS NOT NULL AND EXISTS (SELECT FROM tgsis.rows_at(NULL::public.faults, v.name, r.revision)) "
        "ORDER BY r.revision LIMIT 1"))
    context.figure("fault_first_in", first[0][0] if first else None)
    above = context.ask(f"in which models is the dilatancy above {THRESHOLD}?", sql.SQL(
        "SELECT r.name AS model, round(max(p.dilatancy)::numeric, 3) AS max_dilatancy "
        "FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid), "
        "LATERAL tgsis.rows_at(NULL::public.restored_cellpros, v.name, r.revision) p "
        "WHERE r.name IS NOT NULL GROUP BY r.name, r.revision HAVING max(p.dilatancy) > {} ORDER BY r.revision").format(
            sql.Literal(THRESHOLD)))
    context.figure("dilatancy_above_in", [row[0] for row in above])

    out("5. pictures")
    for label, model, restored_state in (("1", model_11, restored(model_11)), ("2", model_21, restored(model_21)),
                                         ("3", model_31, restored(model_31))):
        surfaces: list[Surface] = [model, restored_state] + ([fault(n)] if label == "3" else [])
        colours = [None, restored_state.vertex_properties["dilatancy"]] + ([None] if label == "3" else [])
        context.wrote(pictures.scene(surfaces, context.folder / f"interpretations_model{label}.png",
                                     colour=colours, colour_label="dilatancy (relative ring-area change)",
                                     title=f"model {label}.1 and its restored state {label}.2"))
    out(f"   {', '.join(p.name for p in context.files)}")
