"""Scenario ``mine``: a resource model revised after each drilling survey, as a chain of versions with validity periods.

The specification's fifth sample application. An initial model of an ore
body from the 2019 boreholes; after each survey (2021, 2023) a child version
of the last one, believed from the survey's date until the next (the latest
with an open end: still believed). A model is a set of objects
(``tgsis.model``, ``tgsis.model_object``, versioned): the resource model holds
the boreholes, the ore body's top and the faults; the geotechnical model the
faults only, so a fault belongs to both. After each survey the new holes are
added, the ore body's top is corrected around them and saved by
difference (only the vertices near the new holes move, only they are stored
again), and a newly mapped fault
joins both models. The questions, in SQL that runs in any session (it does
not move it between versions): which model was believed on a date and what
it held, what changed from one model to the next, and how many rows each
version stored against how many it sees.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import numpy.typing as npt
from psycopg import sql
from scipy.interpolate import LinearNDInterpolator, RBFInterpolator

from tgsis import pictures
from tgsis.db.checkin import save_feature
from tgsis.db.features import create_feature_class, insert_feature
from tgsis.db.modelsets import add_to_model, create_model
from tgsis.db.versions import create_version, enable_feature_versioning, in_version, set_version_validity
from tgsis.mesh import LineSet, Surface
from tgsis.scenarios._context import Context

#: The surveys (the first builds the initial model), their dates, and how many holes each drilled.
SURVEYS = (
    ("survey_2019", dt.datetime(2019, 3, 1, tzinfo=dt.timezone.utc), 8),
    ("survey_2021", dt.datetime(2021, 5, 1, tzinfo=dt.timezone.utc), 6),
    ("survey_2023", dt.datetime(2023, 6, 1, tzinfo=dt.timezone.utc), 6),
)
EXTENT = (1200.0, 800.0)  # m
COLLAR_Z = 400.0  # m, elevation of the collars


def ore_top(xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The true top of the ore body (m, elevation): a dome plunging east, which the holes sample."""
    x, y = xy[:, 0], xy[:, 1]
    return -150.0 - 0.08 * x + 70.0 * np.exp(-(((x - 500.0) / 260.0) ** 2 + ((y - 420.0) / 200.0) ** 2))


def holes(rng: np.random.Generator, count: int) -> npt.NDArray[np.float64]:
    """Collar positions of a campaign's vertical holes."""
    return rng.random((count, 2)) * [EXTENT[0] * 0.9, EXTENT[1] * 0.9] + [EXTENT[0] * 0.05, EXTENT[1] * 0.05]


def borehole(xy: npt.NDArray[np.float64], name: str) -> LineSet:
    """A vertical hole from the collar to 80 m below the ore's top, in 10 segments."""
    z = np.linspace(COLLAR_Z, float(ore_top(xy[None])[0]) - 80.0, 11)
    return LineSet(
        np.column_stack([np.full(11, xy[0]), np.full(11, xy[1]), z]),
        np.column_stack([np.arange(10), np.arange(1, 11)]),
        name=name,
    )


def gridded_top(collars: npt.NDArray[np.float64], nx: int, ny: int) -> Surface:
    """The initial model of the ore body's top: a grid interpolated (thin-plate spline) from the holes' intercepts."""
    u, v = np.meshgrid(np.linspace(0, EXTENT[0], nx), np.linspace(0, EXTENT[1], ny))
    xy = np.column_stack([u.ravel(), v.ravel()])
    z = RBFInterpolator(collars, ore_top(collars), kernel="thin_plate_spline", smoothing=1.0)(xy)
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(
        np.column_stack([xy, np.round(z, 2)]),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="ore top",
    )


def updated_top(previous: Surface, collars: npt.NDArray[np.float64]) -> Surface:
    """The top after a survey: the previous grid corrected around the new holes only (as a modeller updates it).

    Each new intercept's misfit against the previous grid is spread over a
    radius of influence (a Gaussian of 50 m, cut at 120 m); farther away the
    grid keeps its values exactly, so those vertices are not stored again.
    """
    xy, z = previous.vertices[:, :2], previous.vertices[:, 2].copy()
    at = LinearNDInterpolator(xy, z)(collars)
    misfit = ore_top(collars) - at
    distance = np.linalg.norm(xy[:, None, :] - collars[None, :, :], axis=2)
    weight = np.where(distance < 120.0, np.exp(-((distance / 50.0) ** 2)), 0.0)
    correction = (weight * misfit[None, :]).sum(axis=1)
    touched = np.abs(correction) >= 0.005
    z[touched] = np.round(z[touched] + correction[touched], 2)
    return Surface(np.column_stack([xy, z]), previous.cells, name=previous.name)


def fault(x0: float, name: str) -> Surface:
    """A steep fault striking north at x = x0, from the surface to 400 m below."""
    u, w = np.meshgrid(np.linspace(0, EXTENT[1], 5), np.linspace(COLLAR_Z, -400.0, 4))
    xyz = np.column_stack([x0 + 0.25 * (COLLAR_Z - w.ravel()), u.ravel(), w.ravel()])
    idx = np.arange(20).reshape(4, 5)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(xyz, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), name=name)


def run(context: Context) -> None:
    out, conn = context.out, context.conn
    nx, ny = (121, 81) if context.size == "large" else (25, 17)
    rng = np.random.default_rng(2019)
    for name, geotype in (("boreholes", "MULTILINESTRING"), ("orebody", "SURFACE"), ("faults", "SURFACE")):
        create_feature_class(conn, name, geotype, srs=32750)
    enable_feature_versioning(conn)
    out(
        "1. the initial model from the 2019 boreholes; after each survey a new version of the last one, "
        "believed from the survey's date until the next"
    )
    collars = np.zeros((0, 2))
    parent, top_id = "DEFAULT", 0
    tops: list[Surface] = []
    for k, (version, date, count) in enumerate(SURVEYS):
        create_version(conn, version, parent, description=f"the resource model after the {date.year} survey")
        with in_version(conn, version):
            new = holes(rng, count)
            collars = np.vstack([collars, new])
            hole_ids = [
                insert_feature(conn, "boreholes", borehole(xy, f"BH{date.year % 100:02d}-{i + 1:02d}"))
                for i, xy in enumerate(new)
            ]
            top = gridded_top(collars, nx, ny) if k == 0 else updated_top(tops[-1], new)
            tops.append(top)
            if k == 0:
                top_id = insert_feature(conn, "orebody", top)
                fault_id = insert_feature(conn, "faults", fault(850.0, "F1"))
                create_model(
                    conn,
                    "resource model",
                    [*hole_ids, top_id, fault_id],
                    description="boreholes, the ore body's top and the faults",
                )
                create_model(conn, "geotechnical model", [fault_id], description="the faults")
                how = f"{count} holes, the ore body's top gridded from their intercepts, fault F1"
            else:
                saved = save_feature(conn, "orebody", top_id, top)
                add_to_model(conn, "resource model", hole_ids)
                how = (
                    f"{count} new holes; the ore body's top corrected around them and saved by difference "
                    f"({saved.vertices_moved} of its {top.n_vertices} vertices moved)"
                )
                if k == len(SURVEYS) - 1:
                    f2 = insert_feature(conn, "faults", fault(300.0, "F2"))
                    add_to_model(conn, "resource model", [f2])
                    add_to_model(conn, "geotechnical model", [f2])
                    how += "; a new fault F2 mapped, in both models"
            conn.commit()
        following = SURVEYS[k + 1][1] if k + 1 < len(SURVEYS) else None
        set_version_validity(conn, version, date, following)
        conn.commit()
        out(
            f"   {version} (child of {parent}), believed {date.date()} .. "
            f"{following.date() if following else 'still'}: {how}"
        )
        parent = version

    out("2. the questions, in SQL that does not move the session between versions")
    day = dt.datetime(2022, 1, 15, tzinfo=dt.timezone.utc)
    believed = sql.SQL("tgsis.version_believed_at({})").format(sql.Literal(day))
    rows = context.ask(
        f"which resource model was believed on {day.date()}, and what did it hold?",
        sql.SQL(
            "SELECT {b} AS version, count(*) AS objects, "
            "count(*) FILTER (WHERE g.geotype = 'MULTILINESTRING') AS boreholes, "
            "string_agg(g.geoname, ', ' ORDER BY g.geoname) FILTER (WHERE g.geotype = 'SURFACE') AS surfaces "
            "FROM tgsis.rows_at(NULL::tgsis.model, {b}) m "
            "JOIN tgsis.rows_at(NULL::tgsis.model_object, {b}) mo USING (modelid) "
            "JOIN tgsis.rows_at(NULL::tgsis.geometry, {b}) g USING (geoid) "
            "WHERE m.name = 'resource model'"
        ).format(b=believed),
    )
    context.figure("believed_on_2022_01_15", rows[0][0])
    for older, newer in zip(SURVEYS, SURVEYS[1:]):
        rows = context.ask(
            f"what changed from {older[0]} to {newer[0]} (per table: objects and rows)?",
            sql.SQL(
                "SELECT d.shortname AS tbl, count(DISTINCT d.objectkey) AS objects, sum(d.added) AS added, "
                "sum(d.removed) AS removed, sum(d.changed) AS changed FROM tgsis.diff_versions({}, {}) d "
                "GROUP BY 1 ORDER BY 1"
            ).format(sql.Literal(older[0]), sql.Literal(newer[0])),
        )
        context.figure(f"changed_tables_{newer[0]}", [r[0] for r in rows])
    # the stored row versions of tgsis.vrtx: tgsis.vrtx_ver on rows, the decoded chunk versions on chunks (the rows
    # of each chunk version, tgsis.vrtx_chunk_rows); named by tgsis.storage_row_versions, the one place that knows
    (stored_rows,) = conn.execute("SELECT tgsis.storage_row_versions('tgsis', 'vrtx')").fetchone()  # type: ignore[misc]
    rows = context.ask(
        "how many vertex rows did each version store, against how many it sees?",
        sql.SQL(
            "SELECT v.name AS version, (SELECT count(*) FROM {} r JOIN tgsis.revisions rv USING (revision) "
            "WHERE rv.versionid = v.versionid) AS stored, "
            "(SELECT count(*) FROM tgsis.rows_at(NULL::tgsis.vrtx, v.name)) AS seen "
            "FROM tgsis.versions v WHERE v.valid_from IS NOT NULL ORDER BY v.valid_from"
        ).format(sql.SQL(stored_rows)),
    )
    stored, seen = [int(r[1]) for r in rows], [int(r[2]) for r in rows]
    out(
        f"   unchanged parts are not stored again: the later versions stored {stored[1]} and {stored[2]} vertex rows "
        f"while seeing {seen[1]} and {seen[2]} ({100 * sum(stored[1:]) / sum(seen[1:]):.0f} %)"
    )
    context.figure("vertex_rows_stored", stored)
    context.figure("vertex_rows_seen", seen)
    rows = context.ask(
        "which models is fault F1 in, in the latest version?",
        sql.SQL(
            "SELECT string_agg(m.name, ', ' ORDER BY m.name) AS models "
            "FROM tgsis.rows_at(NULL::tgsis.model_object, 'survey_2023') mo "
            "JOIN tgsis.rows_at(NULL::tgsis.model, 'survey_2023') m USING (modelid) "
            "JOIN tgsis.rows_at(NULL::tgsis.geometry, 'survey_2023') g USING (geoid) WHERE g.geoname = 'F1'"
        ),
    )
    context.figure("models_of_F1", rows[0][0])

    png = context.folder / "mine_ore_top.png"
    context.wrote(
        pictures.scene(
            [tops[-1]],
            png,
            title="ore body top after the 2023 survey",
            colour=[pictures.displacement(tops[-1], tops[0])],
            colour_label="moved since 2019 (m)",
            exaggeration=2.0,
        )
    )
    out(f"   {png.name}: the ore body's top in 2023, coloured by how far it moved since the 2019 model")
