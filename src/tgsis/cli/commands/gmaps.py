"""``tgsis gmap``, ``tgsis extrude`` and ``tgsis slice``: G-maps (models 4 and 5)."""

from __future__ import annotations

import argparse
import contextlib
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.cli._arguments import FEATURE_ID, add_command
from tgsis.cli._connection import connection
from tgsis.cli._output import out, print_table, render, show_time
from tgsis.db.features import (
    class_of_feature,
    fetch_feature,
    get_feature_class,
)
from tgsis.errors import (
    InvalidGeometryError,
    InvalidInputError,
    NotFoundError,
)
from tgsis.mesh import Mesh

# --------------------------------------------------------------------------- G-maps (models 4 and 5)


def _gmap_of_file(path: str, fmt: str | None) -> tuple[Any, str | None]:
    """The G-map of the first mesh of a file (its cell properties on the top cells) and the mesh's name."""
    from tgsis import formats, gmaps

    meshes = formats.read(path, fmt)
    if not meshes:
        raise InvalidGeometryError(f"{path} holds no mesh")
    if len(meshes) > 1:
        print(
            f"tgsis: warning: {path} holds {len(meshes)} objects; the first ({meshes[0].name or 'unnamed'}) is taken",
            file=sys.stderr,
        )
    return gmaps.from_mesh(meshes[0]), meshes[0].name


def _gmap_summary(g: Any) -> str:
    counts = ", ".join(f"{g.n_cells(i)} {i}-cells" for i in range(g.dimension + 1))
    return f"a {g.dimension}-G-map in R^{g.embedding_dimension} with {g.n_darts} darts ({counts})"


@dataclass(frozen=True)
class StoredGMap:
    """A G-map stored as feature ``id`` of class ``feature_class``."""

    id: int
    feature_class: str
    gmap: Any


def _gmap_cells_json(g: Any) -> dict[str, Any]:
    """A G-map's dimension, darts and cells per dimension, as ``--json`` gives them."""
    return {"dimension": g.dimension, "darts": g.n_darts, "cells": [g.n_cells(i) for i in range(g.dimension + 1)]}


def cmd_gmap_import(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import insert_gmap

    g, name = _gmap_of_file(args.file, args.format)
    with connection(args) as conn:
        fc = get_feature_class(conn, args.feature_class)
        geoid = insert_gmap(
            conn,
            fc,
            g,
            name=args.name or name,
            drop_extra_properties=args.drop_extra_properties,
            axes=args.axes.split(",") if args.axes else None,
        )
    return render(args, StoredGMap(geoid, fc.name, g), stored_gmap_text, stored_gmap_json)


def stored_gmap_text(args: argparse.Namespace, result: StoredGMap) -> None:
    out(f"stored feature {result.id} of class {result.feature_class}: {_gmap_summary(result.gmap)}")


def stored_gmap_json(result: StoredGMap) -> dict[str, Any]:
    return {"id": result.id, "class": result.feature_class, **_gmap_cells_json(result.gmap)}


@dataclass(frozen=True)
class GMapCheck:
    """What ``tgsis gmap check`` found wrong with feature ``id`` (nothing: a valid G-map)."""

    id: int
    problems: list[Any]


def cmd_gmap_check(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_check

    with connection(args) as conn:
        problems = gmap_check(conn, args.id)
    render(args, GMapCheck(args.id, list(problems)), gmap_check_text, gmap_check_json)
    return 0 if not problems else 1


def gmap_check_text(args: argparse.Namespace, result: GMapCheck) -> None:
    problems = result.problems
    print_table(
        args, ("problem", "count", "darts"), [(p.problem, p.count, ",".join(map(str, p.darts))) for p in problems]
    )
    print(
        f"feature {result.id}: " + ("a valid G-map" if not problems else f"{len(problems)} kind(s) of violation"),
        file=sys.stderr,
    )


def gmap_check_json(result: GMapCheck) -> dict[str, Any]:
    return {
        "id": result.id,
        "valid": not result.problems,
        "problems": [{"problem": p.problem, "count": p.count, "darts": list(p.darts)} for p in result.problems],
    }


@dataclass(frozen=True)
class GMapCells:
    """The ``level``-cells of feature ``id`` (at ``t``): how many darts it has, how many darts each cell has."""

    id: int
    level: int
    t: float | None
    darts: int
    sizes: npt.NDArray[np.int64]


def cmd_gmap_cells(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_cells

    with connection(args) as conn:
        dartids, cells = gmap_cells(conn, args.id, args.level, args.at)
    sizes = np.bincount(cells) if len(cells) else np.zeros(0, dtype=np.int64)
    return render(args, GMapCells(args.id, args.level, args.at, len(dartids), sizes), gmap_cells_text, gmap_cells_json)


def gmap_cells_text(args: argparse.Namespace, result: GMapCells) -> None:
    sizes = result.sizes
    when = "" if result.t is None else f" at t = {show_time(result.t)}"
    if not len(sizes):
        print(f"feature {result.id} does not exist{when}", file=sys.stderr)
    else:
        out(
            f"feature {result.id}{when}: {len(sizes)} {result.level}-cells of {result.darts} darts "
            f"({int(sizes.min())}..{int(sizes.max())} darts each)"
        )


def gmap_cells_json(result: GMapCells) -> dict[str, Any]:
    sizes = result.sizes
    return {
        "id": result.id,
        "level": result.level,
        "t": result.t,
        "cells": len(sizes),
        "darts": result.darts,
        "darts_per_cell": {
            "min": int(sizes.min()) if len(sizes) else None,
            "max": int(sizes.max()) if len(sizes) else None,
        },
    }


def cmd_gmap_at(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_at
    from tgsis.formats.vtk import write_gmap_vtu

    with connection(args) as conn:
        g = gmap_at(conn, args.id, args.time)
    if g is None:
        raise NotFoundError(f"feature {args.id} does not exist at t = {args.time!r}")
    write_gmap_vtu(g, args.file)
    out(f"wrote feature {args.id} at t = {show_time(args.time)}: {_gmap_summary(g)}, to {args.file}")
    return 0


def _values(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InvalidInputError(f"--values {text!r} must be numbers separated by commas, e.g. 0,1,2") from None
    return values


@dataclass(frozen=True)
class Extrusion:
    """A G-map extruded along ``axis`` over ``intervals``: stored as feature ``id`` of ``feature_class`` and/or
    written to ``output``, with its ``axes``."""

    id: int | None
    feature_class: str | None
    output: str | None
    axis: str
    axes: list[str]
    intervals: int
    gmap: Any


def cmd_extrude(args: argparse.Namespace) -> int:
    from tgsis import gmaps
    from tgsis.db.gmaps import fetch_md_gmap, insert_gmap
    from tgsis.formats.vtk import write_gmap_vtu

    if not args.feature_class and not args.output:
        raise InvalidInputError(
            "say where the extrusion goes: --class (a class of multiply indexed G-maps), "
            "--output (a .vtu for ParaView), or both"
        )
    values = _values(args.values)
    axes: list[str] | None = None
    with contextlib.ExitStack() as stack:
        conn = stack.enter_context(connection(args)) if args.feature_class or args.source.isdigit() else None
        if args.source.isdigit() and not Path(args.source).exists():
            assert conn is not None
            fc = class_of_feature(conn, int(args.source))
            if fc.time_model == "MULTIDIM":
                g, named = fetch_md_gmap(conn, fc, int(args.source))
                axes, name = list(named), None
            else:
                mesh = fetch_feature(conn, fc, int(args.source)).mesh
                if not isinstance(mesh, Mesh):
                    raise InvalidGeometryError(f"feature {args.source} is a collection: extrude one of its members")
                g, name = gmaps.from_mesh(mesh), mesh.name
        else:
            g, name = _gmap_of_file(args.source, args.format)
        axes = axes or [("x", "y", "z")[i] if i < 3 else f"axis{i + 1}" for i in range(g.embedding_dimension)]
        if args.axis in axes:
            raise InvalidInputError(f"--axis {args.axis!r} is an axis of the source already: {', '.join(axes)}")
        axes = [*axes, args.axis]
        extruded = gmaps.extrude(g, values)
        if args.output:
            write_gmap_vtu(extruded, args.output, name=name, axes=axes)
        geoid = None
        if args.feature_class:
            assert conn is not None
            geoid = insert_gmap(
                conn, args.feature_class, extruded, name=args.name or name, axes=axes, drop_extra_properties=True
            )
    result = Extrusion(geoid, args.feature_class, args.output, args.axis, axes, len(values) - 1, extruded)
    return render(args, result, extrusion_text, extrusion_json)


def extrusion_text(args: argparse.Namespace, result: Extrusion) -> None:
    where = [
        f"feature {result.id} of class {result.feature_class}" if result.id is not None else "",
        result.output or "",
    ]
    out(
        f"extruded along {result.axis} over {result.intervals} interval(s): {_gmap_summary(result.gmap)}; "
        f"stored as {' and '.join(w for w in where if w)}"
    )


def extrusion_json(result: Extrusion) -> dict[str, Any]:
    return {"id": result.id, "output": result.output, "axes": result.axes, **_gmap_cells_json(result.gmap)}


@dataclass(frozen=True)
class Section:
    """Feature ``id`` cut at ``axis`` = ``value``: the G-map of one dimension less over ``axes``."""

    id: int
    axis: str
    value: float
    output: str | None
    axes: list[str]
    gmap: Any


def cmd_slice(args: argparse.Namespace) -> int:
    from tgsis import gmaps
    from tgsis.db.gmaps import fetch_md_gmap
    from tgsis.formats.vtk import write_gmap_vtu

    with connection(args) as conn:
        g, axes = fetch_md_gmap(conn, class_of_feature(conn, args.id), args.id)
    if args.axis not in axes:
        raise InvalidInputError(f"feature {args.id} has no axis {args.axis!r}; its axes: {', '.join(axes)}")
    at = axes.index(args.axis)
    section = gmaps.slice(g, at, args.value)
    rest = [a for a in axes if a != args.axis]
    if args.output:
        write_gmap_vtu(section, args.output, axes=rest)
    result = Section(args.id, args.axis, args.value, args.output, rest, section)
    return render(args, result, section_text, section_json)


def section_text(args: argparse.Namespace, result: Section) -> None:
    out(
        f"feature {result.id} at {result.axis} = {result.value!r}: {_gmap_summary(result.gmap)}"
        + (f", to {result.output}" if result.output else "")
    )


def section_json(result: Section) -> dict[str, Any]:
    return {
        "id": result.id,
        "axis": result.axis,
        "value": result.value,
        "output": result.output,
        "axes": result.axes,
        **_gmap_cells_json(result.gmap),
    }


def add_gmap_parser(commands: Any) -> None:
    """``tgsis gmap import|check|cells|at``."""
    gmap = add_command(
        commands,
        "gmap",
        "G-maps (models 4 and 5): import from a mesh file, check, cells, snapshot",
        ["tgsis gmap import blocks.ts --class blocks && tgsis gmap check 1"],
    )
    gmap_commands = gmap.add_subparsers(dest="gmap_command", required=True, metavar="COMMAND")
    gmap_import = add_command(
        gmap_commands,
        "import",
        "store the first mesh of a file as a G-map feature (its cells' properties on the top cells)",
        [
            "tgsis gmap import blocks.ts --class blocks",
            "tgsis gmap import cube.vtu --class history --axes x,y,z --json",
        ],
        cmd_gmap_import,
        tabular=False,
    )
    gmap_import.add_argument("file", help="a mesh file (GOCAD, VTK, OBJ, PLY, OFF, STL)")
    gmap_import.add_argument(
        "--class",
        dest="feature_class",
        required=True,
        help="a class of G-maps (time model GMAP or MULTIDIM, with a cell level)",
    )
    gmap_import.add_argument("--name", help="the feature's name (default: the mesh's)")
    gmap_import.add_argument("--format", help="file format (default: from the extension)")
    gmap_import.add_argument("--axes", help="a MULTIDIM class: the names of the axes, comma-separated (default x,y,z)")
    gmap_import.add_argument(
        "--drop-extra-properties",
        action="store_true",
        help="ignore cell properties the class does not store instead of failing",
    )
    gmap_check = add_command(
        gmap_commands,
        "check",
        "check a stored G-map: involutions, fixed points, compositions, periods, points (exit 1 when it breaks one)",
        ["tgsis gmap check 12", "tgsis gmap check 12 --json"],
        cmd_gmap_check,
        tabular=True,
    )
    gmap_check.add_argument("id", type=FEATURE_ID, help="the feature's id")
    gmap_cells = add_command(
        gmap_commands,
        "cells",
        "count the i-cells of a stored G-map (at model time T for model 4)",
        ["tgsis gmap cells 12 2 --at 1.5", "tgsis gmap cells 14 3 --json"],
        cmd_gmap_cells,
        tabular=False,
    )
    gmap_cells.add_argument("id", type=FEATURE_ID, help="the feature's id")
    gmap_cells.add_argument("level", type=int, help="the cell dimension i (0 vertices, 1 edges, 2 faces, 3 volumes)")
    gmap_cells.add_argument("--at", type=float, metavar="T", help="model time (G-maps in time, model 4)")
    gmap_at = add_command(
        gmap_commands,
        "at",
        "write a stored G-map at model time T to a .vtu for ParaView (polygons or polyhedra, properties on cells)",
        ["tgsis gmap at 12 1.5 blocks_1.5.vtu"],
        cmd_gmap_at,
    )
    gmap_at.add_argument("id", type=FEATURE_ID, help="the feature's id")
    gmap_at.add_argument("time", type=float, metavar="T", help="model time (in the class's unit)")
    gmap_at.add_argument("file", help="the .vtu file to write")


def add_extrude_parser(commands: Any) -> None:
    """``tgsis extrude``."""
    extrude = add_command(
        commands,
        "extrude",
        "extrude a mesh or feature along a new axis (model 5): an (n+1)-G-map, "
        "stored in a class and/or written for ParaView",
        [
            "tgsis extrude horizon.ts --axis knowledge --values 2019,2021,2023 --class history",
            "tgsis extrude 12 --axis t --values 0,1 --output prism.vtu",
        ],
        cmd_extrude,
        tabular=False,
    )
    extrude.add_argument("source", help="a mesh file, or the id of a stored feature (model 1 or 5)")
    extrude.add_argument("--axis", required=True, help="the name of the new axis (e.g. knowledge, t)")
    extrude.add_argument(
        "--values", required=True, help="increasing values of the new axis, comma-separated: the layers (at least two)"
    )
    extrude.add_argument("--class", dest="feature_class", help="store it in this class of multiply indexed G-maps")
    extrude.add_argument("--output", help="write it to this .vtu (polyhedra; extra axes as point data)")
    extrude.add_argument("--name", help="the stored feature's name (default: the source's)")
    extrude.add_argument("--format", help="the source file's format (default: from the extension)")


def add_slice_parser(commands: Any) -> None:
    """``tgsis slice``."""
    slice_ = add_command(
        commands,
        "slice",
        "the object of a stored multiply indexed G-map at a value of one of its axes",
        [
            "tgsis slice 14 --axis knowledge --value 2021 --output top_2021.vtu",
            "tgsis slice 14 --axis t --value 0.5 --json",
        ],
        cmd_slice,
        tabular=False,
    )
    slice_.add_argument("id", type=FEATURE_ID, help="the feature's id (a class of time model MULTIDIM)")
    slice_.add_argument("--axis", required=True, help="the axis to cut (one of the feature's axes)")
    slice_.add_argument("--value", required=True, type=float, help="where along it")
    slice_.add_argument("--output", help="write the slice to this .vtu")
