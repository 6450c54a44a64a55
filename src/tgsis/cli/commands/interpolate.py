"""``tgsis interpolate``, ``tgsis corners`` and ``tgsis cut``: surfaces from files."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import tgsis
from tgsis.cli._arguments import INT4, add_command
from tgsis.cli._connection import connection
from tgsis.cli._output import out, render
from tgsis.cli._progress import busy, progress
from tgsis.cli._render import time_unit_suffix
from tgsis.db.features import (
    get_feature_class,
    insert_feature,
)
from tgsis.errors import (
    InvalidInputError,
)

# --------------------------------------------------------------------------- interpolation


def _read_surface(path: str, what: str) -> tgsis.Surface:
    from tgsis import formats

    mesh = formats.read_one(path)
    if not isinstance(mesh, tgsis.Surface):
        raise InvalidInputError(f"the {what} {path} holds a {type(mesh).__name__}: interpolation morphs surfaces")
    return mesh


#: Most PNG views ``tgsis interpolate --preview`` writes.
MAX_PREVIEWS = 1000


def cmd_interpolate(args: argparse.Namespace) -> int:
    from tgsis.interpolation import InterpolationSetup, interpolate
    from tgsis.interpolation.preview import write_previews

    if args.preview and not 1 <= args.frames <= MAX_PREVIEWS:
        raise InvalidInputError(f"--frames must be from 1 to {MAX_PREVIEWS}, got {args.frames}")
    source, target = _read_surface(args.source, "source"), _read_surface(args.target, "target")
    setup = InterpolationSetup.load(args.setup)
    name = args.name or source.name or Path(args.source).stem
    with progress(f"interpolating {name}", None, "step") as moved:
        result = interpolate(
            source, target, setup, args.t0, args.t1, name=name, alive=args.alive, progress=moved, split=args.split
        )
    out(
        f"interpolated {name}: {result.source.n_vertices} vertices, {result.source.n_cells} triangles "
        f"({result.source.n_vertices - source.n_vertices} added by cutting and refinement), m = {setup.steps}, "
        f"error to the target {result.error:.3g}"
    )
    out("  " + ", ".join(f"{stage} {seconds:.2f} s" for stage, seconds in result.timings.items()))
    if args.preview:
        times = np.linspace(args.t0, args.t1, args.frames).tolist()
        paths = write_previews(result.evolving, times, args.preview, stem=Path(args.source).stem)
        out(f"  {len(paths)} previews in {args.preview}")
    if args.feature_class:
        with connection(args) as conn, busy(f"uploading {name}"):
            fid = insert_feature(conn, args.feature_class, result.evolving)
            unit = time_unit_suffix(get_feature_class(conn, args.feature_class))
        # as the user gave the times (the source may be the later shape), then the span in time order
        out(
            f"stored as feature {fid} of class {args.feature_class}: the source ({name}) at t = {args.t0:g}{unit}, "
            f"the target at t = {args.t1:g}{unit}; it exists from t = {min(args.t0, args.t1):g} to "
            f"{max(args.t0, args.t1):g}{unit}" + (" and after (alive)" if args.alive else "")
        )
    return 0


def cmd_corners(args: argparse.Namespace) -> int:
    from tgsis.interpolation import propose_corners

    if args.count is not None and args.count < 1:
        raise InvalidInputError(f"--count must be >= 1, got {args.count}", hint="leave --count out for every corner")
    if not 0 <= args.min_angle <= 180:  # NaN too
        raise InvalidInputError(f"--min-angle must be from 0 to 180 degrees, got {args.min_angle}")
    surface = _read_surface(args.file, "surface")
    corners = propose_corners(surface, min_angle=args.min_angle, count=args.count)
    return render(args, Corners(args.file, surface, corners.tolist()), corners_text, corners_json)


@dataclass(frozen=True)
class Corners:
    """The vertices of ``surface`` (read from ``file``) proposed as its corners."""

    file: str
    surface: tgsis.Surface
    vertices: list[int]


def corners_text(args: argparse.Namespace, result: Corners) -> None:
    """The indices on standard output (as JSON: a setup takes them), every coordinate on standard error."""
    out(json.dumps(result.vertices))
    for vertex in result.vertices:
        x, y, z = result.surface.vertices[vertex].tolist()  # every digit: repr of the float (6 digits are ~10 m in UTM)
        print(f"vertex {vertex}: {x!r} {y!r} {z!r}", file=sys.stderr)


def corners_json(result: Corners) -> dict[str, Any]:
    return {
        "file": result.file,
        "corners": [{"vertex": v, "xyz": result.surface.vertices[v].tolist()} for v in result.vertices],
    }


def _vertex_path(text: str) -> list[int]:
    try:
        path = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"a path is vertex indices separated by commas (e.g. 3,7,12), got {text!r}"
        ) from None
    if len(path) < 2 or min(path) < 0:
        raise argparse.ArgumentTypeError(f"a path has at least two vertex indices >= 0, got {text!r}")
    return path


def cmd_cut(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.interpolation.cutting import cut_along_paths

    target = formats.format_for(args.output, args.format)  # an unknown format fails before any work
    surface = _read_surface(args.file, "surface")
    cut = cut_along_paths(surface, args.path, names=[f"--path {','.join(map(str, p))}" for p in args.path])
    target.write(cut.surface, args.output)
    out(
        f"cut {args.file} along {len(args.path)} path(s): {surface.n_vertices} vertices, {cut.n_copies} copied "
        f"({cut.surface.n_vertices} now), {surface.n_cells} triangles; wrote {args.output}"
    )
    return 0


def add_interpolate_parser(commands: Any) -> None:
    """``tgsis interpolate``."""
    interp = add_command(
        commands,
        "interpolate",
        "the surface evolving from SOURCE (at T0) to TARGET (at T1): "
        "morphological interpolation, stored as a model-3 feature",
        ["tgsis interpolate flat.ts dome.ts --setup dome.json --t0 0 --t1 1 --class salt --preview out"],
        cmd_interpolate,
    )
    interp.add_argument("source", help="surface file at T0")
    interp.add_argument("target", help="surface file at T1")
    interp.add_argument(
        "--setup",
        required=True,
        help="JSON set-up: control vertices, fences, cuts, attachments, steps, tolerance (see docs/interpolation.md)",
    )
    interp.add_argument("--t0", type=float, required=True, help="time of the source")
    interp.add_argument("--t1", type=float, required=True, help="time of the target")
    interp.add_argument(
        "--class",
        dest="feature_class",
        help="EVOLVING feature class to store it in (without: computed and previewed only)",
    )
    interp.add_argument("--name", help="feature name (default: the source's)")
    interp.add_argument(
        "--split",
        choices=("auto", "centroid"),
        default="auto",
        help="how the compatible meshes are refined: centroid is the design's rule (split the "
        "triangle at its centroid), auto (default) bisects its longest interior edge instead, "
        "which converges where centroid splits stall",
    )
    interp.add_argument(
        "--alive", action="store_true", help="the surface goes on existing after its last instant, in its last shape"
    )
    interp.add_argument("--preview", metavar="DIR", help="write PNG views of a few instants to DIR")
    interp.add_argument("--frames", type=INT4, default=5, help="number of preview instants (default 5)")


def add_corners_parser(commands: Any) -> None:
    """``tgsis corners``."""
    corners = add_command(
        commands,
        "corners",
        "propose control vertices: the sharp corners of a surface's border",
        ["tgsis corners horizon.ts --count 4", "tgsis corners horizon.ts --json"],
        cmd_corners,
        tabular=False,
    )
    corners.add_argument("file", help="a file holding one surface")
    corners.add_argument("--count", type=INT4, help="exactly this many corners")
    corners.add_argument("--min-angle", type=float, default=35.0, help="smallest turn of a corner, degrees (35)")


def add_cut_parser(commands: Any) -> None:
    """``tgsis cut``."""
    cut = add_command(
        commands,
        "cut",
        "cut a surface along vertex paths (its edges become borders on both sides)",
        ["tgsis cut horizon.ts horizon_cut.ts --path 12,13,14,15"],
        cmd_cut,
    )
    cut.add_argument("file", metavar="FILE", help="a file holding one surface")
    cut.add_argument("output", metavar="OUTPUT", help="the cut surface is written here")
    cut.add_argument(
        "--path",
        type=_vertex_path,
        action="append",
        required=True,
        metavar="V1,V2,...",
        help="a cutting path: vertex indices of FILE along interior edges, only its ends on the border "
        "(repeat for several paths)",
    )
    cut.add_argument("--format", help="format of OUTPUT (default: from its extension)")
