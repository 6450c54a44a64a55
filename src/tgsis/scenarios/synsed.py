"""Scenario ``synsed``: horizons deposited one after another while a normal fault slips.

The specification's second sample application. A normal fault keeps its
position and slips at a constant rate; horizons A..E are laid down by
t = 0..4 and each is cut by the fault into two blocks, the hanging wall
lowered by the throw accumulated since the horizon was laid down (older
horizons carry more displacement) and every horizon buried as younger ones
pile up. The model is known at t = 1, 2, 3 and 4 with a growing number of
horizons. Each horizon is interpolated in each interval between two known
instants (eight control pairs: the corners of its two blocks) and the
intervals are chained into one evolving feature over its whole life; the
fault is one surface constant over [1, 4].

A horizon that first appears at a known instant was deposited during the
interval before it: as the source design does, it is interpolated from its
own top at the interval's end (the source) to the horizon beneath at the
interval's start (the target), so it starts as the surface it lies on and
grows (:func:`tgsis.deposit`); and no horizon passes below an older one
(:func:`tgsis.keep_above`, the contacts reported). The questions: the whole
structure at t = 2.5, every surface that exists then (D is being
deposited), from one SQL query (``tgsis.surfaces_at``), equal to the Python
snapshots; the throw of each horizon then, from SQL.
"""

from __future__ import annotations

import numpy as np
from psycopg import sql

from tgsis import pictures
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.temporal import get_at
from tgsis.interpolation import InterpolationSetup
from tgsis.interpolation.deposition import deposit, keep_above
from tgsis.interpolation.interpolate import interpolate
from tgsis.mesh import Surface
from tgsis.scenarios._context import Context
from tgsis.temporal import EvolvingSurface

WIDTH, LENGTH = 4000.0, 2000.0
FAULT_X = 2000.0  # the fault's trace; the blocks stop GAP/2 short of it (the heave)
GAP = 200.0
BURIAL = 100.0  # m of burial per Myr
THROW_RATE = 60.0  # m of throw per Myr
TIME_UNIT = "Myr"
HORIZONS = {"A": 0.0, "B": 1.0, "C": 2.0, "D": 3.0, "E": 4.0}  # name -> time its top is laid down (oldest first)
KNOWN = (1.0, 2.0, 3.0, 4.0)
QUERY_TIME = 2.5


def _block(nx: int, ny: int, x0: float, x1: float) -> tuple[np.ndarray, np.ndarray, list[int]]:
    u, v = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(0, LENGTH, ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return np.stack([u.ravel(), v.ravel()], 1), triangles, [0, nx - 1, nx * ny - 1, nx * (ny - 1)]


def horizon_at(name: str, t: float, nx: int, ny: int) -> tuple[Surface, list[int]]:
    """Horizon ``name`` as it lies at ``t`` (its two blocks) and the eight corners of the blocks."""
    age = t - HORIZONS[name]
    vertices, triangles, corners, offset = [], [], [], 0
    for x0, x1, hanging in ((0.0, FAULT_X - GAP / 2, False), (FAULT_X + GAP / 2, WIDTH, True)):
        xy, tri, block_corners = _block(nx, ny, x0, x1)
        # buried, lowered on the hanging wall by the throw since deposition, with a roll alike on both sides
        z = -BURIAL * age - (THROW_RATE * age if hanging else 0.0) + 15.0 * np.cos((xy[:, 0] - FAULT_X) / 700.0)
        vertices.append(np.column_stack([xy, z]))
        triangles.append(tri + offset)
        corners += [c + offset for c in block_corners]
        offset += len(xy)
    return Surface(np.concatenate(vertices), np.concatenate(triangles), name=f"horizon {name}"), corners


def fault(ny: int) -> Surface:
    """The fault: a plane dipping towards the hanging wall, across the gap between the blocks."""
    depth = np.array([50.0, -300.0, -650.0])
    x = FAULT_X - GAP / 2 + GAP * (50.0 - depth) / 700.0
    u, v = np.meshgrid(np.arange(3), np.linspace(0, LENGTH, ny))
    idx = np.arange(3 * ny).reshape(ny, 3)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(
        np.stack([x[u.ravel()], v.ravel(), depth[u.ravel()]], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="fault F",
    )


def deposition(name: str) -> tuple[str, float, float] | None:
    """(horizon beneath, start, end) of the interval during which ``name`` was deposited; None if known from the first instant."""
    laid = HORIZONS[name]
    if laid <= KNOWN[0]:
        return None
    names = list(HORIZONS)
    return names[names.index(name) - 1], max(t for t in KNOWN if t < laid), min(t for t in KNOWN if t >= laid)


def evolving_horizon(name: str, nx: int, ny: int) -> tuple[EvolvingSurface, float]:
    """The horizon grown from the one beneath, then interpolated between the known instants, chained; the worst error."""
    parts: list[EvolvingSurface] = []
    worst = 0.0
    known = [t for t in KNOWN if t >= HORIZONS[name]]
    for t0, t1 in zip(known, known[1:]):
        (source, source_corners), (target, target_corners) = horizon_at(name, t0, nx, ny), horizon_at(name, t1, nx, ny)
        if parts:  # the shape the period before ends with: the two share it at t0
            before = parts[-1].at(t0)
            assert before is not None
            source = Surface(before.vertices, before.cells, name=source.name)
        setup = InterpolationSetup(tuple(source_corners), tuple(target_corners), steps=3, tolerance=1.0)
        result = interpolate(source, target, setup, t0, t1, name=source.name)
        parts.append(result.evolving)
        worst = max(worst, float(result.error))
    grown = deposition(name)
    if grown is not None:  # the design: its top at the end the source, the surface beneath the target
        beneath_name, start, end = grown
        top, top_corners = horizon_at(name, end, nx, ny)
        if parts:  # the top as the next period starts: the two share their shape at `end`
            first = parts[0].at(end)
            assert first is not None
            top = Surface(first.vertices, first.cells, name=top.name)
        beneath, beneath_corners = horizon_at(beneath_name, start, nx, ny)
        setup = InterpolationSetup(tuple(top_corners), tuple(beneath_corners), steps=3, tolerance=1.0)
        laid = deposit(top, beneath, setup, start, end, name=top.name)
        parts.insert(0, laid.evolving)
        worst = max(worst, float(laid.interpolation.error))
    return EvolvingSurface.chain(parts, alive=True, name=f"horizon {name}"), worst


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    nx, ny = (24, 16) if context.size == "large" else (7, 5)
    fc = create_feature_class(
        conn,
        "structure",
        "SURFACE",
        time_model="EVOLVING",
        time_unit=TIME_UNIT,
        description="a normal fault and the horizons deposited while it slipped",
    )
    out(
        f"1. known at t = {', '.join(f'{t:g}' for t in KNOWN)} {TIME_UNIT}: "
        + "; ".join(f"t = {t:g}: {', '.join(n for n, d in HORIZONS.items() if d <= t)}" for t in KNOWN)
    )
    evolving: dict[str, EvolvingSurface] = {}
    ids, worst, raised = {}, 0.0, {}
    for name in HORIZONS:  # oldest first: each kept above those before it
        surface, error = evolving_horizon(name, nx, ny)
        worst = max(worst, error)
        stacking = keep_above(surface, list(evolving.values()))
        evolving[surface.name or name] = stacking.surface
        raised[surface.name or name] = stacking.max_raise
    f = fault(ny)
    evolving[f.name or "fault"] = EvolvingSurface.constant(f, KNOWN[0], KNOWN[-1], alive=True)
    for label, surface in evolving.items():
        ids[label] = insert_feature(conn, fc, surface)
    conn.commit()
    out(
        "   each horizon interpolated in each interval (8 control pairs: its blocks' corners) and chained: "
        + ", ".join(f"{label} {len(s.periods)} period(s)" for label, s in evolving.items())
        + f"; stored as features {min(ids.values())}..{max(ids.values())} of class structure"
    )
    out(
        "   "
        + ", ".join(
            f"{name} grows from {grown[0]} over [{grown[1]:g}, {grown[2]:g}]"
            for name in HORIZONS
            for grown in [deposition(name)]
            if grown is not None
        )
        + " (its top at the end the source, the horizon beneath at the start the target); "
        + f"no horizon below an older one: raised at most {max(raised.values()):.3g} m onto one"
    )
    context.figure("interpolation_error_m", worst)
    context.figure("raised_m", raised)

    out(f"2. the whole structure at t = {QUERY_TIME:g} {TIME_UNIT}")
    context.structure_at("structure", QUERY_TIME, evolving)

    out(f"3. the throw of each horizon at t = {QUERY_TIME:g} {TIME_UNIT}")
    throws = context.ask(
        "mean depth of the footwall block minus that of the hanging wall",
        sql.SQL(
            "SELECT g.geoname AS horizon, round((avg(v.z) FILTER (WHERE v.x < {fault}) "
            "- avg(v.z) FILTER (WHERE v.x > {fault}))::numeric, 1) AS throw_m "
            "FROM tgsis.features_at('structure', {t}) AS f(geoid) JOIN tgsis.geometry g USING (geoid), "
            "LATERAL tgsis.vertices_at(g.geoid, {t}) v WHERE g.geoname LIKE 'horizon %' "
            "GROUP BY g.geoname ORDER BY g.geoname"
        ).format(fault=sql.Literal(FAULT_X), t=sql.Literal(QUERY_TIME)),
    )
    context.figure("throws_m", {row[0]: float(row[1]) for row in throws})
    out(
        "   older horizons carry more displacement: " + " > ".join(f"{row[0].split()[-1]} {row[1]} m" for row in throws)
    )

    out("4. pictures")
    for t in (1.0, QUERY_TIME, 4.0):
        scene = [s for s in (get_at(conn, ids[label], t) for label in evolving) if s is not None]
        png = context.folder / f"synsed_t{t:g}.png".replace(".", "_", 1).replace("_png", ".png")
        context.wrote(
            pictures.scene(
                scene, png, title=f"the structure at t = {t:g} {TIME_UNIT} (SQL snapshots)", exaggeration=2.0
            )
        )
    out(f"   {', '.join(p.name for p in context.files)}")
