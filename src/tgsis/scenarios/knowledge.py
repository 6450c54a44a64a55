"""Scenario ``knowledge``: a horizon's successive interpretations as one object over a knowledge axis (model 5).

An anticline's top is picked again after each seismic campaign (2019, 2021,
2023, 2025): each reprocessing moves the crest. Rather than four separate
surfaces, model 5 makes knowledge an axis: the horizon's 2-G-map is extruded
along it (:func:`tgsis.gmaps.extrude`), each layer holding one
interpretation, so the history is one 3-G-map in (x, y, z, knowledge) whose
volumes are the horizon between two campaigns (with how far its depth
changed across them as a property). The questions: which histories reach a
box over some of their axes (an index over every axis serves any subset),
how deep the crest was in each campaign (the points in a box over x, y and
knowledge), what the history is made of (its cells, from SQL), and whether
the slice at a campaign gives that interpretation back (Python). Pictures:
the interpretations in one scene, coloured by how far each moved since the
first; ParaView gets them as a series over the knowledge axis.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis import gmaps, pictures
from tgsis.db.features import create_feature_class
from tgsis.db.gmaps import insert_gmap
from tgsis.mesh import Surface
from tgsis.scenarios._context import Context
from tgsis.temporal import write_frames_pvd

#: The campaigns (the knowledge axis), the horizon's extent (m) and the crest window (m).
CAMPAIGNS = (2019.0, 2021.0, 2023.0, 2025.0)
EXTENT = (3000.0, 2000.0)
CREST = ((1100.0, 700.0), (1900.0, 1300.0))
AXES = ("x", "y", "z", "knowledge")


def interpretations(nx: int, ny: int) -> tuple[gmaps.GMap, list[npt.NDArray[np.float64]]]:
    """The horizon's triangulation (a 2-G-map) and its points as picked after each campaign.

    An anticline whose crest each reprocessing finds deeper and a little
    further east (velocity model updates), over a regional dip.
    """
    u, v = np.meshgrid(np.linspace(0, EXTENT[0], nx), np.linspace(0, EXTENT[1], ny))
    x, y = u.ravel(), v.ravel()
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    horizon = gmaps.GMap.from_triangles(np.stack([x, y, np.zeros_like(x)], 1), triangles)
    layers = []
    for k in range(len(CAMPAIGNS)):
        crest_x = 1450.0 + 40.0 * k
        bump = np.exp(-(((x - crest_x) / 700.0) ** 2 + ((y - 1000.0) / 450.0) ** 2))
        z = -2000.0 - 0.05 * x + (420.0 - 35.0 * k) * bump
        layers.append(np.stack([x, y, z], 1))
    return horizon, layers


def history(horizon: gmaps.GMap, layers: list[npt.NDArray[np.float64]]) -> gmaps.GMap:
    """The interpretations as one 3-G-map over (x, y, z, knowledge): layer k holds campaign k's points.

    Its volumes (horizon triangle x interval) carry ``change_m``: how far the
    triangle's mean depth moved between the two campaigns.
    """
    extruded = gmaps.extrude(horizon, list(CAMPAIGNS))
    points = np.vstack(
        [np.column_stack([layer, np.full(len(layer), campaign)]) for layer, campaign in zip(layers, CAMPAIGNS)]
    )
    triangles = horizon.simplices()
    depth = np.stack([layer[triangles, 2].mean(axis=1) for layer in layers])  # (campaigns, triangles)
    change = np.concatenate([depth[j + 1] - depth[j] for j in range(len(CAMPAIGNS) - 1)])
    return gmaps.GMap(extruded.alpha, extruded.vertex, points, cell_properties={3: {"change_m": change}})


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    nx, ny = (61, 41) if context.size == "large" else (13, 9)
    horizon, layers = interpretations(nx, ny)
    out(
        f"1. the top of an anticline picked after each campaign {', '.join(f'{c:g}' for c in CAMPAIGNS)}: "
        f"{horizon.n_points} points, {horizon.n_cells(2)} triangles each"
    )
    whole = history(horizon, layers)
    out(
        f"   one object over knowledge: the horizon's 2-G-map extruded along it, a 3-G-map in R^4 with "
        f"{whole.n_darts} darts and {whole.n_cells(3)} volumes (a triangle between two campaigns)"
    )
    create_feature_class(
        conn,
        "horizon_history",
        "GMAP",
        time_model="MULTIDIM",
        cell_level=3,
        cell_properties={"change_m": "float8"},
        feature_properties={"horizon": "text"},
        description="interpretations of a horizon over a knowledge axis (model 5)",
    )
    geoid = insert_gmap(
        conn, "horizon_history", whole, {"horizon": "top anticline"}, name="top anticline", axes=list(AXES)
    )
    moved = whole.points.copy()
    moved[:, 0] += 5000.0
    other = insert_gmap(
        conn,
        "horizon_history",
        gmaps.GMap(whole.alpha, whole.vertex, moved, cell_properties=whole.cell_properties),
        {"horizon": "top syncline east"},
        name="top syncline east",
        axes=list(AXES),
    )
    conn.commit()
    out(f"   stored as features {geoid} and {other} (a second history 5 km east) of class horizon_history")

    out("2. box queries over some of the axes (one GiST index over all four serves any subset)")
    (lo_x, lo_y), (hi_x, hi_y) = CREST
    rows = context.ask(
        "which histories reach the crest window in x and y after 2022?",
        sql.SQL(
            "SELECT f._geoid AS feature, f.horizon FROM tgsis.md_in_box('horizon_history', {}, {}, {}) b(geoid) "
            "JOIN horizon_history f ON f._geoid = b.geoid ORDER BY 1"
        ).format(
            sql.Literal(["x", "y", "knowledge"]), sql.Literal([lo_x, lo_y, 2022.0]), sql.Literal([hi_x, hi_y, 2026.0])
        ),
    )
    context.figure("histories_in_the_window", [r[1] for r in rows])
    rows = context.ask(
        "how deep was the crest in each campaign (the points in a box over x, y and knowledge)?",
        sql.SQL(
            "SELECT v.coordinate[4]::integer AS campaign, count(*) AS points, round(max(v.coordinate[3])::numeric, 1) AS crest_m "
            "FROM tgsis.md_vertices_in_box({}, {}, {}, {}) v GROUP BY 1 ORDER BY 1"
        ).format(
            sql.Literal(geoid),
            sql.Literal(["x", "y", "knowledge"]),
            sql.Literal([lo_x, lo_y, CAMPAIGNS[0]]),
            sql.Literal([hi_x, hi_y, CAMPAIGNS[-1]]),
        ),
    )
    crest = [float(r[2]) for r in rows]
    context.figure("crest_m", crest)
    out(f"   each campaign found the crest deeper: {' > '.join(f'{c:g}' for c in crest)} m")
    rows = context.ask(
        "what is the history made of (its i-cells, from SQL)?",
        sql.SQL(
            "SELECT l.level, count(DISTINCT c.cell) AS cells FROM generate_series(0, 3) l(level), "
            "LATERAL tgsis.md_cells({}, l.level) c GROUP BY 1 ORDER BY 1"
        ).format(sql.Literal(geoid)),
    )
    counts = [int(r[1]) for r in rows]
    euler = counts[0] - counts[1] + counts[2] - counts[3]
    out(
        f"   vertices {counts[0]}, edges {counts[1]}, faces {counts[2]}, volumes {counts[3]}: Euler characteristic "
        f"{euler} (a disk times an interval: 1; Python says {whole.euler_characteristic()})"
    )
    context.figure("cells", counts)

    out("3. the slice at each campaign is that interpretation again (Python, tgsis.gmaps.slice)")
    surfaces = []
    for campaign, layer in zip(CAMPAIGNS, layers):
        section = gmaps.slice(whole, 3, campaign)
        surface = section.to_mesh()
        assert isinstance(surface, Surface)
        same = bool(np.array_equal(np.sort(section.points[:, :3], axis=0), np.sort(layer, axis=0)))
        surfaces.append(Surface(surface.vertices[:, :3], surface.cells, name=f"top {campaign:g}"))
        out(f"   {campaign:g}: {section.n_cells(2)} triangles, the picked points: {'yes' if same else 'NO'}")
        context.figure(f"slice_{campaign:g}_is_the_interpretation", same)

    first = surfaces[0]
    png = context.folder / "knowledge_interpretations.png"
    context.wrote(
        pictures.scene(
            surfaces,
            png,
            title="top anticline picked in 2019-2025",
            colour=[pictures.displacement(s, first) for s in surfaces],
            colour_label="moved since 2019 (m)",
            exaggeration=2.0,
        )
    )
    series = write_frames_pvd(
        [(campaign, s) for campaign, s in zip(CAMPAIGNS, surfaces)], context.folder / "knowledge.pvd"
    )
    context.wrote([series.pvd])
    out(f"   {', '.join(p.name for p in context.files)} (knowledge.pvd: the campaigns as ParaView time steps)")
