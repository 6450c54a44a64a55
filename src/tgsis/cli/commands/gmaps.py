"""``tgsis gmap``, ``tgsis extrude`` and ``tgsis slice``: G-maps (models 4 and 5)."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import Any

import numpy as np

from tgsis.cli._arguments import FEATURE_ID, add_command
from tgsis.cli._connection import connection
from tgsis.cli._output import emit_json, out, print_table, show_time, wants_json
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
    if wants_json(args):
        emit_json(
            {
                "id": geoid,
                "class": fc.name,
                "dimension": g.dimension,
                "darts": g.n_darts,
                "cells": [g.n_cells(i) for i in range(g.dimension + 1)],
            }
        )
    else:
        out(f"stored feature {geoid} of class {fc.name}: {_gmap_summary(g)}")
    return 0


def cmd_gmap_check(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_check

    with connection(args) as conn:
        problems = gmap_check(conn, args.id)
    if wants_json(args):
        emit_json(
            {
                "id": args.id,
                "valid": not problems,
                "problems": [{"problem": p.problem, "count": p.count, "darts": list(p.darts)} for p in problems],
            }
        )
        return 0 if not problems else 1
    print_table(
        args, ("problem", "count", "darts"), [(p.problem, p.count, ",".join(map(str, p.darts))) for p in problems]
    )
    print(
        f"feature {args.id}: " + ("a valid G-map" if not problems else f"{len(problems)} kind(s) of violation"),
        file=sys.stderr,
    )
    return 0 if not problems else 1


def cmd_gmap_cells(args: argparse.Namespace) -> int:
    from tgsis.db.gmaps import gmap_cells

    with connection(args) as conn:
        dartids, cells = gmap_cells(conn, args.id, args.level, args.at)
    sizes = np.bincount(cells) if len(cells) else np.zeros(0, dtype=np.int64)
    when = "" if args.at is None else f" at t = {show_time(args.at)}"
    if wants_json(args):
        emit_json(
            {
                "id": args.id,
                "level": args.level,
                "t": args.at,
                "cells": len(sizes),
                "darts": len(dartids),
                "darts_per_cell": {
                    "min": int(sizes.min()) if len(sizes) else None,
                    "max": int(sizes.max()) if len(sizes) else None,
                },
            }
        )
    elif not len(cells):
        print(f"feature {args.id} does not exist{when}", file=sys.stderr)
    else:
        out(
            f"feature {args.id}{when}: {len(sizes)} {args.level}-cells of {len(dartids)} darts "
            f"({int(sizes.min())}..{int(sizes.max())} darts each)"
        )
    return 0


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
    summary = _gmap_summary(extruded)
    if wants_json(args):
        emit_json(
            {
                "id": geoid,
                "output": args.output,
                "axes": axes,
                "dimension": extruded.dimension,
                "darts": extruded.n_darts,
                "cells": [extruded.n_cells(i) for i in range(extruded.dimension + 1)],
            }
        )
    else:
        where = [f"feature {geoid} of class {args.feature_class}" if geoid is not None else "", args.output or ""]
        out(
            f"extruded along {args.axis} over {len(values) - 1} interval(s): {summary}; "
            f"stored as {' and '.join(w for w in where if w)}"
        )
    return 0


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
    if wants_json(args):
        emit_json(
            {
                "id": args.id,
                "axis": args.axis,
                "value": args.value,
                "output": args.output,
                "axes": rest,
                "dimension": section.dimension,
                "darts": section.n_darts,
                "cells": [section.n_cells(i) for i in range(section.dimension + 1)],
            }
        )
    else:
        out(
            f"feature {args.id} at {args.axis} = {args.value!r}: {_gmap_summary(section)}"
            + (f", to {args.output}" if args.output else "")
        )
    return 0


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
