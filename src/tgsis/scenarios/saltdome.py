"""Scenario ``saltdome``: a flat salt layer (t = 0) rising into today's dome (t = 1).

The specification's first sample application. The two known shapes have
different triangulations: the layer is a regular grid, the dome a Delaunay
triangulation of scattered points. Four corner control pairs tie them; the
morphological interpolation builds the evolving surface between them, which
is stored as a model-3 feature. The questions: the shape at t = 2/3 and
t = 1/2 from SQL (``tgsis.vertices_at``) and from Python
(:meth:`tgsis.EvolvingSurface.at`), which must be equal to the bit; how high
the salt has risen by then. Pictures: the two known shapes and the two
snapshots coloured by how far each point has moved since t = 0, and an
animation; ParaView gets the series.
"""

from __future__ import annotations

import numpy as np
from psycopg import sql
from scipy.spatial import Delaunay

from tgsis import pictures
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.temporal import export_series, get_at
from tgsis.interpolation import InterpolationSetup
from tgsis.interpolation.interpolate import interpolate
from tgsis.mesh import Surface
from tgsis.scenarios._context import Context

#: The layer's extent (m) and depth of its top (m, elevation), the dome's rise (m).
EXTENT = (4000.0, 2000.0)
DEPTH = -2500.0
RISE = 1500.0
TIME_UNIT = "Myr"


def salt_layer(nx: int, ny: int) -> Surface:
    """The flat top of the salt at t = 0: a regular grid; corners are vertices 0, nx-1, nx*ny-1, nx*(ny-1)."""
    u, v = np.meshgrid(np.linspace(0, EXTENT[0], nx), np.linspace(0, EXTENT[1], ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(
        np.stack([u.ravel(), v.ravel(), np.full(u.size, DEPTH)], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="salt layer",
    )


def salt_dome(inside: int, side: int, seed: int = 7) -> Surface:
    """Today's dome: scattered points over the same extent, Delaunay-triangulated; corners are vertices 0..3."""
    rng = np.random.default_rng(seed)
    w, h = EXTENT
    corners = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=float)
    along = np.linspace(0, 1, side + 2)[1:-1]
    sides = np.concatenate(
        [
            np.stack([along * w, np.zeros(side)], 1),
            np.stack([np.full(side, w), along * h], 1),
            np.stack([(1 - along) * w, np.full(side, h)], 1),
            np.stack([np.zeros(side), (1 - along) * h], 1),
        ]
    )
    points = rng.random((inside, 2)) * [w * 0.96, h * 0.92] + [w * 0.02, h * 0.04]
    xy = np.concatenate([corners, sides, points])
    # a dome with a steeper western flank, centred a little off the middle
    r2 = ((xy[:, 0] - 0.55 * w) / (0.22 * w)) ** 2 + ((xy[:, 1] - 0.5 * h) / (0.3 * h)) ** 2
    z = DEPTH + RISE * np.exp(-r2)
    tri = Delaunay(xy).simplices
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    down = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[down] = tri[down][:, [0, 2, 1]]
    return Surface(np.column_stack([xy, z]), tri, name="salt dome")


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    large = context.size == "large"
    nx, ny = (61, 31) if large else (21, 11)
    layer, dome = salt_layer(nx, ny), salt_dome(1500 if large else 150, 24 if large else 10)
    setup = InterpolationSetup((0, nx - 1, nx * ny - 1, nx * (ny - 1)), (0, 1, 2, 3), steps=5, tolerance=10.0)
    out(
        f"1. the salt's top: flat at t = 0 ({layer.n_vertices} vertices, a grid), a dome at t = 1 "
        f"({dome.n_vertices} vertices, Delaunay): four corner control pairs"
    )
    result = interpolate(layer, dome, setup, 0.0, 1.0, name="salt")
    evolving = result.evolving
    context.figure("interpolation_error_m", float(result.error))
    out(
        f"   interpolated: {len(evolving.periods)} topology period, {result.target.n_vertices} vertices on a common "
        f"triangulation, compatible target within {result.error:.2f} m of the dome"
    )

    fc = create_feature_class(conn, "salt", "SURFACE", time_model="EVOLVING", time_unit=TIME_UNIT)
    fid = insert_feature(conn, fc, evolving)
    conn.commit()
    out(f"2. stored as feature {fid} of class salt (EVOLVING, {TIME_UNIT})")

    start = get_at(conn, fid, 0.0)
    assert start is not None
    snapshots = []
    for label, t in (("2/3", 2.0 / 3.0), ("1/2", 0.5)):
        rows = context.ask(
            f"the salt's top at t = {label} {TIME_UNIT}, in SQL",
            sql.SQL(
                "SELECT count(*) AS vertices, round(max(z)::numeric, 1) AS top_m, "
                "round(min(z)::numeric, 1) AS lowest_m FROM tgsis.vertices_at({}, {})"
            ).format(sql.Literal(fid), sql.Literal(t)),
        )
        from_sql, from_python = get_at(conn, fid, t), evolving.at(t)
        assert from_sql is not None and from_python is not None
        same = bool(
            np.array_equal(from_sql.vertices, from_python.vertices)
            and np.array_equal(from_sql.cells, from_python.cells)
        )
        out(
            f"   from Python (EvolvingSurface.at): {from_python.n_vertices} vertices, top "
            f"{from_python.vertices[:, 2].max():.1f} m; equal to SQL to the bit: {'yes' if same else 'NO'}"
        )
        context.figure(f"sql_equals_python_at_{label}", same)
        context.figure(f"top_m_at_{label}", float(rows[0][1]))
        snapshots.append((label, t, from_sql))

    out("3. pictures and the series")
    known = context.folder / "saltdome_known_shapes.png"
    context.wrote(pictures.scene([layer, dome], known, title=f"salt: flat at t = 0 and the dome at t = 1 {TIME_UNIT}"))
    for label, _t, surface in snapshots:
        png = context.folder / f"saltdome_t{label.replace('/', '_')}.png"
        context.wrote(
            pictures.scene(
                [surface],
                png,
                colour=[pictures.displacement(surface, start)],
                colour_label="moved since t = 0 (m)",
                title=f"salt's top at t = {label} {TIME_UNIT} (SQL snapshot)",
            )
        )
    times = np.linspace(0.0, 1.0, 11)
    frames = []
    for t in times:
        snapshot = get_at(conn, fid, float(t))
        assert snapshot is not None
        frames.append((float(t), [snapshot]))
    context.wrote(
        pictures.animation(
            frames,
            context.folder / "saltdome.gif",
            title="salt's top",
            time_unit=TIME_UNIT,
            reference=[start],
            colour_label="moved since t = 0 (m)",
        )
    )
    series = export_series(conn, fid, context.folder / "saltdome.pvd", start=0.0, end=1.0, steps=len(times))
    context.wrote([series.pvd])
    out(f"   {', '.join(p.name for p in context.files)} (open saltdome.pvd in ParaView)")
    context.figure("frames", len(times))
