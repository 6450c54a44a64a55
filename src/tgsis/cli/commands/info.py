"""``tgsis info`` and ``tgsis ls``: what features there are and what each is."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Any

import psycopg

from tgsis.cli._arguments import FEATURE_ID, add_command, box, property_filters
from tgsis.cli._connection import connection
from tgsis.cli._output import out, print_table, render, show_time
from tgsis.cli._render import time_model_suffix, time_unit_suffix
from tgsis.db import versions as V
from tgsis.db.classes import FeatureClass
from tgsis.db.features import (
    class_of_feature,
    fetch_feature,
    get_feature_class,
    list_feature_classes,
)
from tgsis.db.inspect import (
    FeatureRow,
    GeometrySummary,
    feature_property_values,
    features_versioned,
    geometry_summary,
    list_features,
    shape_sizes,
)
from tgsis.db.temporal import instants, lifespan
from tgsis.errors import InvalidInputError
from tgsis.mesh import Mesh


def _sizes_in_time(conn: psycopg.Connection[Any], time_model: str, geoid: int) -> str | None:
    """How many vertices and cells one shape of a surface in time has (model 2: per instant, model 3: per topology
    period), where tgsis.geometry adds up the rows of every instant or period; None for other models."""
    sizes = shape_sizes(conn, time_model, geoid)
    if sizes is None:
        return None
    each, unit = ("per instant", "instants") if time_model == "INSTANTS" else ("per topology period", "periods")
    vertices, cells, k = list(sizes.vertices), list(sizes.cells), sizes.count
    if min(vertices) == max(vertices) and min(cells) == max(cells):
        return f"{vertices[0]} vertices, {cells[0]} cells " + (
            f"at each of its {k} {unit}" if unit == "instants" else f"in each of its {k} {unit}"
        )
    return f"{min(vertices)} to {max(vertices)} vertices, {min(cells)} to {max(cells)} cells {each} ({k} {unit})"


@dataclass(frozen=True)
class Differing:
    """A version where a feature differs: ``what`` for people (``only there``, ``not there``, ``N rows differ``)."""

    version: str
    what: str
    rows: int


@dataclass(frozen=True)
class FeatureInfo:
    """What ``tgsis info`` says of one feature; ``differing`` is None when its class is not versioned."""

    id: int
    fc: FeatureClass
    summary: GeometrySummary
    sizes: str | None
    span: tuple[float, float, bool] | None
    steps: list[tuple[float, bool]]
    properties: dict[str, Any]
    vertex_properties: list[str]
    cell_properties: list[str]
    version: str
    differing: list[Differing] | None


def cmd_info(args: argparse.Namespace) -> int:
    from tgsis.db.versions import diff_versions, list_versions, working_version

    with connection(args) as conn:
        fc = class_of_feature(conn, args.id)
        summary = geometry_summary(conn, args.id)
        feature = fetch_feature(conn, fc, args.id) if fc.time_model == "STATIC" else None
        properties = feature_property_values(conn, fc, args.id)
        span = lifespan(conn, args.id)
        steps = instants(conn, args.id) if span is not None else []
        sizes = _sizes_in_time(conn, fc.time_model, args.id)
        here = working_version(conn)
        versioned = fc.versioned and features_versioned(conn)
        differing: list[Differing] = []
        if versioned:
            for version in list_versions(conn):
                if version.name != here:
                    changed = [
                        d
                        for d in diff_versions(conn, here, version.name)
                        if d.objectclass == "feature" and d.objectkey == str(args.id)
                    ]
                    if changed:
                        added, removed = sum(d.added for d in changed), sum(d.removed for d in changed)
                        what = (
                            "only there"
                            if removed == 0 and sum(d.changed for d in changed) == 0 and added
                            else "not there"
                            if added == 0 and sum(d.changed for d in changed) == 0 and removed
                            else f"{sum(d.added + d.removed + d.changed for d in changed)} rows differ"
                        )
                        rows = sum(d.added + d.removed + d.changed for d in changed)
                        differing.append(Differing(version.name, what, rows))
        conn.rollback()
    found = feature.mesh if feature is not None else None
    mesh = found if isinstance(found, Mesh) else None
    info = FeatureInfo(
        args.id,
        fc,
        summary,
        sizes,
        span,
        list(steps),
        properties,
        list(mesh.vertex_properties) if mesh is not None else [],
        list(mesh.cell_properties) if mesh is not None else [],
        here,
        differing if versioned else None,
    )
    return render(args, info, info_text, info_json)


def info_text(args: argparse.Namespace, info: FeatureInfo) -> None:
    fc, summary, span, steps = info.fc, info.summary, info.span, info.steps
    box = summary.box
    out(
        f"feature {info.id}: {summary.name or '(no name)'}, class {fc.name} "
        f"({summary.geotype}{time_model_suffix(fc)}), in version {V.show_name(info.version)}"
    )
    out(
        f"  {info.sizes or f'{summary.n_vertices} vertices, {summary.n_cells} cells'}"
        + (f", {summary.members} members" if summary.members is not None else "")
    )
    if box[0] is not None:
        out("  box: " + ", ".join(f"{axis} [{box[2 * i]!r}, {box[2 * i + 1]!r}]" for i, axis in enumerate("xyz")))
    if span is None:
        out("  static: the same at every time")
    else:
        topology = [t for t, starts in steps if starts]
        out(
            f"  exists from t = {show_time(span[0])} to {show_time(span[1])}{time_unit_suffix(fc)}"
            + (" and after (alive)" if span[2] else "")
            + f"; {len(steps)} instants, topology (re)defined at {', '.join(show_time(t) for t in topology)}"
        )
    if info.properties:
        out("  properties: " + ", ".join(f"{k} = {v!r}" for k, v in info.properties.items()))
    if fc.instant_properties:
        out("  per-instant properties: " + ", ".join(p.name for p in fc.instant_properties))
    if info.vertex_properties:
        out("  vertex properties: " + ", ".join(info.vertex_properties))
    if info.cell_properties:
        out("  cell properties: " + ", ".join(info.cell_properties))
    if info.differing is not None:
        differs = [f"{V.show_name(d.version)} ({d.what})" for d in info.differing]
        out(
            "  versions where it differs from "
            + V.show_name(info.version)
            + ": "
            + (", ".join(differs) if differs else "none")
        )
    elif not fc.versioned:
        out(f"  class {fc.name} is not versioned: every version sees this state")


def info_json(info: FeatureInfo) -> dict[str, Any]:
    fc, summary, span, box = info.fc, info.summary, info.span, info.summary.box
    return {
        "id": info.id,
        "name": summary.name,
        "class": fc.name,
        "geotype": summary.geotype,
        "time_model": fc.time_model,
        "time_unit": fc.time_unit,
        "version": info.version,
        "vertices": summary.n_vertices,
        "cells": summary.n_cells,
        "members": summary.members,
        "box": None if box[0] is None else {axis: [box[2 * i], box[2 * i + 1]] for i, axis in enumerate("xyz")},
        "lifespan": None if span is None else {"first": span[0], "last": span[1], "alive": span[2]},
        "instants": [{"t": t, "topology": starts} for t, starts in info.steps],
        "properties": info.properties,
        "instant_properties": [p.name for p in fc.instant_properties],
        "vertex_properties": info.vertex_properties,
        "cell_properties": info.cell_properties,
        "versioned": info.differing is not None,
        "differs_in": None
        if info.differing is None
        else [
            {
                "version": d.version,
                "what": d.what if d.what in ("only there", "not there") else "differs",
                "rows": d.rows,
            }
            for d in info.differing
        ],
    }


def _shown_properties(properties: dict[str, Any]) -> str:
    """``release=6.1 slip=2.0``: a feature's properties in one table cell (a NULL as nothing after ``=``)."""
    return " ".join(f"{k}={'' if v is None else v}" for k, v in properties.items())


@dataclass(frozen=True)
class FeatureList:
    """The features ``tgsis ls`` found."""

    features: list[FeatureRow]


def cmd_ls(args: argparse.Namespace) -> int:
    wanted = property_filters(args.property)
    if wanted and not args.feature_class:
        raise InvalidInputError(
            "--property needs --class: feature properties belong to a class",
            hint="tgsis class list names the classes and their properties",
        )
    with connection(args) as conn:
        classes = [get_feature_class(conn, args.feature_class)] if args.feature_class else list_feature_classes(conn)
        rows = []
        for fc in classes:
            rows += list_features(conn, fc, name=args.name, box=args.box, properties=wanted)
    return render(args, FeatureList(rows), ls_text, ls_json)


def _darts(geotype: str, ncell: int | None) -> tuple[int | None, int | None]:
    """(cells, darts): a G-map's geometry row counts its darts where other geometries count cells
    (tgsis gmap cells counts its cells)."""
    return (None, ncell) if geotype == "GMAP" else (ncell, None)


def ls_text(args: argparse.Namespace, result: FeatureList) -> None:
    rows = result.features
    print_table(
        args,
        ("id", "class", "name", "geotype", "vertices", "cells", "members", "darts", "properties"),
        [
            (
                r.id,
                r.feature_class,
                r.name or "",
                r.geotype,
                r.vertices,
                *("" if n is None else n for n in _darts(r.geotype, r.cells)[:1]),
                "" if r.members is None else r.members,
                *("" if n is None else n for n in _darts(r.geotype, r.cells)[1:]),
                _shown_properties(r.properties),
            )
            for r in rows
        ],
    )
    if not rows:
        print("no features", file=sys.stderr)


def ls_json(result: FeatureList) -> dict[str, Any]:
    return {
        "features": [
            {
                "id": r.id,
                "class": r.feature_class,
                "name": r.name,
                "geotype": r.geotype,
                "vertices": r.vertices,
                "cells": _darts(r.geotype, r.cells)[0],
                "members": r.members,
                "darts": _darts(r.geotype, r.cells)[1],
                "properties": r.properties,
            }
            for r in result.features
        ]
    }


def add_info_parser(commands: Any) -> None:
    """``tgsis info``."""
    info = add_command(
        commands,
        "info",
        "what a feature is: class, counts, box, lifespan and instants, properties, the versions where it differs",
        ["tgsis info 3", "tgsis info 3 --json"],
        cmd_info,
        tabular=False,
    )
    info.add_argument("id", type=FEATURE_ID, help="the feature's id")


def add_ls_parser(commands: Any) -> None:
    """``tgsis ls``."""
    ls = add_command(
        commands,
        "ls",
        "list features",
        [
            "tgsis ls",
            "tgsis ls --class faults --json",
            "tgsis ls --class faults --property release=6.1 --name garlock",
            "tgsis ls --box 0,0,-5000,10000,10000,0",
            "tgsis --in cfm6 ls --no-header | cut -f1",
        ],
        cmd_ls,
        tabular=True,
    )
    ls.add_argument("--class", dest="feature_class", help="only this feature class")
    ls.add_argument("--name", help="only features whose name contains NAME, in any case")
    ls.add_argument(
        "--box",
        type=box,
        metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
        help="only features whose bounding box meets this box (write --box=-1,... when XMIN is negative)",
    )
    ls.add_argument(
        "--property",
        action="append",
        metavar="NAME=VALUE",
        help="only features whose feature property NAME equals VALUE, read as the property's type "
        "(repeatable; with --class)",
    )
