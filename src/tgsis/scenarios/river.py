"""Scenario ``river``: three units deposited on a fixed basement, partly eroded, their contacts changing.

The specification's third sample application. A basement that does not
move; the tops of three sedimentary units known at six instants t = 0..5.
Each unit is a strip across the valley that thins out to nothing at its
western and eastern edges (pinch-outs), where its top meets whatever lies
below: the basement, or an older unit. Unit 1 is there from t = 0 and is
partly eroded between t = 1 and 2 (its top is lowered in the middle); unit
2 is deposited between t = 0 and 1 and overlaps unit 1's eastern part;
unit 3 is deposited between t = 2 and 3 on unit 2 and the basement and
progrades west beyond unit 2's pinch-out by t = 4, onto unit 1: which unit
lies on which changes between t = 3 and 4.

A unit first known at an instant was deposited during the interval before
it: as the source design does, it is interpolated from its top at the
interval's end (the source) to the surfaces it lies on at its start (the
target, :func:`tgsis.drape`: unit 1 and the basement under unit 2, unit 2
and the basement under unit 3), so it starts as the surface beneath and
thickens (:func:`tgsis.deposit`). Then each unit is interpolated in each
interval between two known instants (its four corners as control pairs);
the edge vertices that lie on the basement at both instants are attached to
it, so the pinch-out slides along the basement instead of cutting through
it. Unit 3 between t = 3 and 4 is interpolated from its later, larger shape
(the source may be the later shape). Each unit's intervals are chained into
one evolving feature, and no unit's top passes below an older one
(:func:`tgsis.keep_above`): where it would, it is put on it, and that
erosion/onlap contact is reported. The basement is one surface constant
over [0, 5]. The questions, in SQL: the structure at t = 1.5 and 2.5 (one
query each, equal to the Python snapshots) and which unit lies on which at
t = 3 and at t = 4.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from psycopg import sql

from tgsis import pictures
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.temporal import get_at
from tgsis.interpolation import InterpolationSetup
from tgsis.interpolation.deposition import deposit, drape, keep_above
from tgsis.interpolation.interpolate import interpolate
from tgsis.interpolation.setup import Attachment
from tgsis.mesh import Surface
from tgsis.scenarios._context import Context
from tgsis.temporal import EvolvingSurface

WIDTH, LENGTH = 5000.0, 2000.0
TIME_UNIT = "kyr"
TIMES = (0.0, 1.0, 2.0, 3.0, 4.0, 5.0)
#: per unit and known time: (west edge, east edge, greatest thickness in m); a unit absent at a time is left out
UNITS: dict[str, dict[float, tuple[float, float, float]]] = {
    "unit 1": {
        0.0: (600, 2400, 40),
        1.0: (500, 2800, 70),
        2.0: (500, 2800, 70),
        3.0: (500, 2800, 70),
        4.0: (500, 2800, 70),
        5.0: (500, 2800, 70),
    },
    "unit 2": {
        1.0: (1800, 3600, 30),
        2.0: (1700, 3900, 60),
        3.0: (1700, 3900, 60),
        4.0: (1700, 3900, 60),
        5.0: (1700, 3900, 60),
    },
    "unit 3": {3.0: (2400, 4600, 30), 4.0: (1100, 4700, 50), 5.0: (1000, 4700, 60)},
}
#: unit 1's top is lowered in its middle between t = 1 and t = 2 (a river cuts into it)
EROSION = {2.0: 25.0, 3.0: 25.0, 4.0: 25.0, 5.0: 25.0}
QUERY_TIMES = (1.5, 2.5)


#: the basement's nodes along x: it is linear between them, so points set on it lie on its triangles
BASEMENT_X = np.linspace(0.0, WIDTH, 101)


def basement_z(x: np.ndarray) -> np.ndarray:
    return np.asarray(np.interp(x, BASEMENT_X, -300.0 + 20.0 * np.sin(BASEMENT_X / 900.0)), dtype=np.float64)


def thickness(unit: str, t: float, x: np.ndarray) -> np.ndarray:
    """Thickness of ``unit`` at ``t`` along x: a rounded profile between its edges, zero outside."""
    if t not in UNITS[unit]:
        return np.zeros_like(x)
    west, east, height = UNITS[unit][t]
    s = np.clip((x - west) / (east - west), 0.0, 1.0)
    profile = np.where((s > 0) & (s < 1), height * np.sin(np.pi * s) ** 0.7, 0.0)  # exactly 0 at its edges
    if unit == "unit 1" and t in EROSION:  # the channel cut into unit 1's top
        profile = profile - EROSION[t] * np.exp(-(((x - 1500.0) / 300.0) ** 2))
    return np.asarray(np.maximum(profile, 0.0), dtype=np.float64)


def top_z(unit: str, t: float, x: np.ndarray) -> np.ndarray:
    """The top of ``unit`` at ``t``: the basement plus the thickness of it and every older unit."""
    z = basement_z(x)
    for name in UNITS:
        z = z + thickness(name, t, x)
        if name == unit:
            return np.asarray(z, dtype=np.float64)
    raise KeyError(unit)


def _strip(x0: float, x1: float, nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(0, LENGTH, ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return np.stack([u.ravel(), v.ravel()], 1), np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def unit_top(unit: str, t: float, nx: int, ny: int) -> Surface:
    """The top of ``unit`` at ``t`` as a strip grid between its edges (corners 0, nx-1, nx*ny-1, nx*(ny-1))."""
    west, east, _ = UNITS[unit][t]
    xy, triangles = _strip(west, east, nx, ny)
    return Surface(np.column_stack([xy, top_z(unit, t, xy[:, 0])]), triangles, name=unit)


def basement(ny: int) -> Surface:
    xy, triangles = _strip(0.0, WIDTH, len(BASEMENT_X), ny)
    return Surface(np.column_stack([xy, basement_z(xy[:, 0])]), triangles, name="basement")


def _on_basement(surface: Surface, vertices: list[int]) -> list[int]:
    v = surface.vertices[vertices]
    return [i for i, z in zip(vertices, v[:, 2] - basement_z(v[:, 0])) if abs(z) < 1e-9]


def deposition(unit: str) -> tuple[float, float] | None:
    """(start, end) of the interval during which ``unit`` was deposited; None if it is there at the first instant."""
    first = min(UNITS[unit])
    return None if first <= TIMES[0] else (max(t for t in TIMES if t < first), first)


def _setup(glued: list[int], corners: tuple[int, ...]) -> InterpolationSetup:
    return InterpolationSetup(
        corners,
        corners,
        controlling_surfaces={"basement": "basement (given in memory)"},
        attachments=tuple(Attachment(v, ("basement",)) for v in glued),
        steps=4,
        tolerance=1.0,
    )


def _off_basement(trajectories: np.ndarray, glued: list[int]) -> float:
    path = trajectories[:, glued]  # (m, k, 3): every geometry instant
    return float(np.abs(path[..., 2] - basement_z(path[..., 0])).max(initial=0.0))


def evolving_unit(
    unit: str, floor: Surface, older: list[EvolvingSurface], nx: int, ny: int
) -> tuple[EvolvingSurface, int, float]:
    """The unit grown from the surfaces beneath, interpolated per interval and chained; vertices attached, how far they strayed.

    Each period starts with the very vertices the one before ends with (its
    compatible target, not a fresh grid of the same top), so that the
    stored periods share their geometry at every boundary instant.
    """
    known = sorted(UNITS[unit])
    corners = (0, nx - 1, nx * ny - 1, nx * (ny - 1))
    edges = [j * nx for j in range(ny)] + [j * nx + nx - 1 for j in range(ny)]
    parts: list[EvolvingSurface] = []
    attached, strayed = 0, 0.0
    for t0, t1 in zip(known, known[1:]):
        earlier, later = unit_top(unit, t0, nx, ny), unit_top(unit, t1, nx, ny)
        if parts:  # the shape the period before ends with: the two share it at t0
            before = parts[-1].at(t0)
            assert before is not None
            earlier = Surface(before.vertices, before.cells, name=unit)
        backwards = unit == "unit 3" and (t0, t1) == (3.0, 4.0)  # the later, larger shape as the source
        source, target, ts, tt = (later, earlier, t1, t0) if backwards else (earlier, later, t0, t1)
        # edge vertices on the basement in both shapes slide along it
        glued = sorted(set(_on_basement(source, edges)) & set(_on_basement(target, edges)) - set(corners))
        attached += len(glued)
        result = interpolate(source, target, _setup(glued, corners), ts, tt, name=unit, surfaces={"basement": floor})
        parts.append(result.evolving)
        strayed = max(strayed, _off_basement(result.trajectories, glued))
    grown = deposition(unit)
    if grown is not None:  # the design: its top at the end the source, the surface beneath the target
        start, end = grown
        # the top as the next period starts (its vertices, so that the two periods share their shape at `end`)
        top = parts[0].at(end) if parts else unit_top(unit, end, nx, ny)
        assert top is not None
        beneath = [s for s in (o.at(start) for o in older) if s is not None]
        glued = sorted(set(_on_basement(top, edges)) & set(_on_basement(drape(top, beneath), edges)) - set(corners))
        attached += len(glued)
        laid = deposit(top, beneath, _setup(glued, corners), start, end, name=unit, surfaces={"basement": floor})
        parts.insert(0, laid.evolving)
        strayed = max(strayed, _off_basement(laid.interpolation.trajectories, glued))
    return EvolvingSurface.chain(parts, alive=True, name=unit), attached, strayed


def _lies_on(t: float) -> sql.Composed:
    """What each unit's top lies on at t: under each of its vertices, the highest older surface at or below it.

    The surface under a point is found by its triangle there (barycentric
    coordinates) and the height interpolated in it; older means stored
    before (the units were deposited in the order they were stored). A
    triangle's box is grown by 1e-6 m: a vertex on the model's border that
    rounding put 1e-13 m outside the older surface's border still lies on it.
    """
    return sql.SQL(
        "WITH f AS (SELECT g.geoid, g.geoname AS surface FROM tgsis.features_at('river', {t}) AS f(geoid) "
        "JOIN tgsis.geometry g USING (geoid)), "
        "v AS (SELECT f.geoid, f.surface, v.vrtxid, v.x, v.y, v.z FROM f, LATERAL tgsis.vertices_at(f.geoid, {t}) v), "
        "k AS (SELECT f.geoid, f.surface, a.x AS ax, a.y AS ay, a.z AS az, b.x AS bx, b.y AS by, b.z AS bz, "
        "c.x AS cx, c.y AS cy, c.z AS cz FROM f CROSS JOIN LATERAL tgsis.triangles_at(f.geoid, {t}) r "
        "JOIN v a ON a.geoid = f.geoid AND a.vrtxid = r.vrtxid1 JOIN v b ON b.geoid = f.geoid AND b.vrtxid = r.vrtxid2 "
        "JOIN v c ON c.geoid = f.geoid AND c.vrtxid = r.vrtxid3), "
        "w AS (SELECT p.surface, p.vrtxid, p.z, k.surface AS under, "
        "((k.by - k.cy) * (p.x - k.cx) + (k.cx - k.bx) * (p.y - k.cy)) / d AS l1, "
        "((k.cy - k.ay) * (p.x - k.cx) + (k.ax - k.cx) * (p.y - k.cy)) / d AS l2, k.az, k.bz, k.cz "
        "FROM v p JOIN k ON k.geoid < p.geoid "
        "AND p.x BETWEEN least(k.ax, k.bx, k.cx) - 1e-6 AND greatest(k.ax, k.bx, k.cx) + 1e-6 "
        "AND p.y BETWEEN least(k.ay, k.by, k.cy) - 1e-6 AND greatest(k.ay, k.by, k.cy) + 1e-6, "
        "LATERAL (SELECT (k.by - k.cy) * (k.ax - k.cx) + (k.cx - k.bx) * (k.ay - k.cy) AS d) dd), "
        "h AS (SELECT surface, vrtxid, z, under, l1 * az + l2 * bz + (1 - l1 - l2) * cz AS under_z FROM w "
        "WHERE l1 >= -1e-9 AND l2 >= -1e-9 AND l1 + l2 <= 1 + 1e-9), "
        "top AS (SELECT DISTINCT ON (surface, vrtxid) surface, under FROM h WHERE under_z <= z + 1e-6 "
        "ORDER BY surface, vrtxid, under_z DESC) "
        "SELECT surface AS unit, string_agg(DISTINCT under, ', ' ORDER BY under) AS lies_on FROM top "
        "GROUP BY surface ORDER BY surface"
    ).format(t=sql.Literal(t))


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    nx, ny = (61, 21) if context.size == "large" else (25, 6)
    floor = basement(ny)
    fc = create_feature_class(
        conn,
        "river",
        "SURFACE",
        time_model="EVOLVING",
        time_unit=TIME_UNIT,
        description="a fixed basement and the tops of three units deposited and eroded on it",
    )
    out(
        f"1. known at t = {', '.join(f'{t:g}' for t in TIMES)} {TIME_UNIT}: "
        + "; ".join(f"{u} known from t = {min(k):g}" for u, k in UNITS.items())
        + "; unit 1 partly eroded by t = 2"
    )
    evolving = {"basement": EvolvingSurface.constant(floor, TIMES[0], TIMES[-1], alive=True)}
    glued: dict[str, int] = {}
    onlap: dict[str, dict[str, Any]] = {}
    strayed, dip = 0.0, -np.inf
    for unit in UNITS:  # oldest first: each grows from, and is kept above, those before it
        grown, glued[unit], off = evolving_unit(unit, floor, list(evolving.values()), nx, ny)
        strayed = max(strayed, off)
        stacking = keep_above(grown, list(evolving.values()))
        dip = max(dip, stacking.residual)
        names = list(evolving)
        onlap[unit] = {
            "raised_m": round(stacking.max_raise, 3),
            "vertex_instants": stacking.clamped,
            "on": [names[i] for i in stacking.lies_on()],
        }
        evolving[unit] = stacking.surface
    ids = {name: insert_feature(conn, fc, surface) for name, surface in evolving.items()}
    conn.commit()
    out(
        "   "
        + ", ".join(
            f"{u} deposited over [{grown[0]:g}, {grown[1]:g}]"
            for u in UNITS
            for grown in [deposition(u)]
            if grown is not None
        )
        + ": each starts on the surfaces beneath (its top at the end the source, those surfaces at the start "
        + "the target) and thickens"
    )
    out(
        "   each unit interpolated per interval, its pinch-out edges attached to the basement ("
        + ", ".join(f"{u} {n} vertex-intervals" for u, n in glued.items())
        + f"; at most {strayed:.1e} m off it at any instant of the interpolation), "
        + "unit 3 from its later shape between t = 3 and 4; "
        + f"chained and stored as features {min(ids.values())}..{max(ids.values())} of class river"
    )
    out(
        "   no top below an older one; the erosion/onlap contact (where a top lies on an older one): "
        + "; ".join(
            f"{u} on {', '.join(c['on'])}, raised {c['vertex_instants']} vertex-instants by at most {c['raised_m']:g} m"
            for u, c in onlap.items()
        )
        + f"; between instants (sampled at 1/4, 1/2, 3/4 of each) at most {max(dip, 0.0):.2g} m below"
    )
    context.figure("attached", glued)
    context.figure("pinch_out_off_basement_m", strayed)
    context.figure("onlap_contact", onlap)
    context.figure("dip_between_instants_m", max(dip, 0.0))

    for label, t in zip("ab", QUERY_TIMES):
        out(f"2{label}. the structure at t = {t:g} {TIME_UNIT}")
        context.structure_at("river", t, evolving)

    out("3. which unit lies on which")
    for t in (3.0, 4.0):
        contacts = context.ask(f"at t = {t:g} {TIME_UNIT}: the surface directly under each unit's top", _lies_on(t))
        context.figure(f"lies_on_at_{t:g}", {row[0]: row[1] for row in contacts})

    out("4. pictures")
    for t in (1.5, 2.5, 3.0, 4.0):
        scene = [s for s in (get_at(conn, ids[name], t) for name in evolving) if s is not None]
        context.wrote(
            pictures.section(
                scene,
                context.folder / f"river_t{t:g}.png".replace(".", "_", 1).replace("_png", ".png"),
                y=LENGTH / 2,
                title=f"the units at t = {t:g} {TIME_UNIT} (SQL snapshots)",
                exaggeration=8.0,
            )
        )
    out(f"   {', '.join(p.name for p in context.files)}")
