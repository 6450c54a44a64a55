"""``tgsis at``, ``tgsis series`` and ``tgsis query``: features in model time."""

from __future__ import annotations

import argparse
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tgsis.cli._arguments import FEATURE_ID, INT4, add_command
from tgsis.cli._connection import connection
from tgsis.cli._output import out, print_table, render, show_time
from tgsis.cli._progress import progress
from tgsis.cli._render import picture_of, time_unit_suffix
from tgsis.db.features import (
    FeatureClass,
    class_of_feature,
)
from tgsis.db.temporal import export_series, get_at, lifespan
from tgsis.errors import (
    InvalidInputError,
    NotFoundError,
)
from tgsis.mesh import Surface
from tgsis.temporal import WrittenSeries, even_times


@dataclass(frozen=True)
class PropertyQuery:
    """The features of a class whose per-instant ``property`` is ``op`` ``value``, with the periods when it is
    (``first``: show the first moment only)."""

    feature_class: str
    property: str
    op: str
    value: float
    convention: str
    first: bool
    found: dict[int, list[Any]]


def cmd_query(args: argparse.Namespace) -> int:
    from tgsis.db.temporal import class_property_periods

    if math.isnan(args.value):
        raise InvalidInputError("VALUE must be a number, got nan", hint="-inf and inf are allowed")
    with connection(args) as conn:
        found = class_property_periods(
            conn, args.feature_class, args.property, args.op, args.value, convention=args.convention
        )
    return render(
        args,
        PropertyQuery(args.feature_class, args.property, args.op, args.value, args.convention, args.first, found),
        query_text,
        query_json,
    )


def query_text(args: argparse.Namespace, result: PropertyQuery) -> None:
    found = result.found
    if result.first:
        print_table(
            args,
            ("id", "first", "when"),
            [
                (fid, show_time(periods[0].start), "" if periods[0].start_closed else "(right after it)")
                for fid, periods in found.items()
            ],
        )
    else:
        print_table(
            args, ("id", "periods"), [(fid, " ".join(str(p) for p in periods)) for fid, periods in found.items()]
        )
    if not found:
        print(
            f"no feature of {result.feature_class} has {result.property} {result.op} {result.value!r} at any time",
            file=sys.stderr,
        )


def query_json(result: PropertyQuery) -> dict[str, Any]:
    found = result.found
    return {
        "class": result.feature_class,
        "property": result.property,
        "op": result.op,
        "value": result.value,
        "convention": result.convention,
        "features": [
            {
                "id": fid,
                "first": {"t": periods[0].start, "right_after": not periods[0].start_closed},
                "periods": [
                    {"start": p.start, "end": p.end, "start_closed": p.start_closed, "end_closed": p.end_closed}
                    for p in periods
                ],
            }
            for fid, periods in found.items()
        ],
    }


# --------------------------------------------------------------------------- time


def _life(span: tuple[float, float, bool] | None, fc: FeatureClass) -> str:
    """When a feature exists, for messages."""
    if span is None:
        return "it is static: it exists at every time"
    first, last, alive = span
    return (
        f"it exists from t = {first!r}{time_unit_suffix(fc)} on (alive)"
        if alive
        else f"it exists from t = {first!r} to {last!r}{time_unit_suffix(fc)}"
    )


def cmd_at(args: argparse.Namespace) -> int:
    from tgsis import formats

    if not math.isfinite(args.time):
        raise InvalidInputError(f"T must be a finite number, got {args.time!r}")
    if (args.format or Path(args.file).suffix).lower().lstrip(".") == "pvd":
        raise InvalidInputError(
            f"{args.file}: tgsis at writes one surface; a .pvd is a time series", hint="tgsis series writes a .pvd"
        )
    # the file says when the snapshot is: {t} in its name, or a folder's file feature_ID_tT.FORMAT
    file = args.file.replace("{t}", repr(args.time))
    if Path(file).is_dir():
        if not args.format:
            raise InvalidInputError(
                f"{args.file} is a folder: give --format (e.g. --format vtu) for the file "
                f"feature_{args.id}_t{args.time!r}.FORMAT written in it"
            )
        file = str(Path(file) / f"feature_{args.id}_t{args.time!r}.{args.format.lower().lstrip('.')}")
    target = formats.format_for(file, args.format)  # an unknown format fails before connecting
    with connection(args) as conn:
        fc = class_of_feature(conn, args.id)
        surface = get_at(conn, args.id, args.time, convention=args.convention, properties=True)
        if surface is None:
            raise NotFoundError(
                f"feature {args.id} ({fc.name}) does not exist at t = {args.time!r}{time_unit_suffix(fc)}",
                hint=_life(lifespan(conn, args.id), fc),
            )
        _with_z_convention(conn, args.id, surface)
        # and its name, which GOCAD writes in its header and VTK in its field data (and a legacy file's title)
        surface.name = f"{surface.name or f'feature {args.id}'} at t = {args.time!r}{time_unit_suffix(fc)}"
        target.write(surface, file)
        out(
            f"wrote feature {args.id} ({fc.name}) at t = {args.time!r}{time_unit_suffix(fc)}: {surface.n_vertices} vertices, "
            f"{surface.n_cells} triangles, to {file}"
        )
        if args.png:
            picture_of(
                conn,
                [args.id, *args.with_ids],
                args.time,
                args.png,
                title=f"feature {args.id} ({fc.name}) at t = {args.time!r}{time_unit_suffix(fc)} (SQL snapshot)",
            )
    return 0


def _with_z_convention(conn: Any, feature_id: int, surface: Surface) -> None:
    """The snapshot (stored z: elevation) in the z convention its feature was stored with, as an export gives it.

    GOCAD then writes ``ZPOSITIVE`` as the imported file had it; the formats
    without a z convention write elevation whatever it is (tgsis._zpositive).
    """
    from tgsis.db.inspect import stored_zpositive
    from tgsis.db.meaning import restore_meaning

    zpositive = stored_zpositive(conn, feature_id)
    if zpositive is not None:
        restore_meaning(surface, zpositive, None, None, None)


def _series_name(name: str) -> str:
    """The stem of the .pvd file (a trailing .pvd dropped); no folders."""
    stem = name[:-4] if name.lower().endswith(".pvd") else name
    if not stem or stem in (".", "..") or "/" in stem or os.sep in stem:
        raise InvalidInputError(f"--name {name!r} must be a file name without folders, e.g. fault_history")
    return stem


@dataclass(frozen=True)
class WrittenFrames:
    """Feature ``id``'s series as written (and drawn to ``gif``, when given)."""

    id: int
    fc: FeatureClass
    written: WrittenSeries
    gif: str | None


def cmd_series(args: argparse.Namespace) -> int:
    sampling = (args.start, args.end, args.steps)
    if any(v is not None for v in sampling):
        if any(v is None for v in sampling):
            raise InvalidInputError(
                "--from, --to and --steps go together",
                hint="without all three, the frames are at the feature's own instants",
            )
        even_times(args.start, args.end, args.steps, labels=("--from", "--to", "--steps"))  # clear messages
    stem = _series_name(args.name or f"feature_{args.id}")
    folder = Path(args.dir)
    with connection(args) as conn:
        fc = class_of_feature(conn, args.id)
        if args.steps is None and lifespan(conn, args.id) is None:
            raise InvalidInputError(
                f"feature {args.id} ({fc.name}) is static: it has no instants of its own",
                hint="give --from, --to and --steps",
            )
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"cannot create the folder {folder}: {exc.strerror or exc}") from exc
        with progress("writing frames", args.steps, "frame") as moved:
            written = export_series(
                conn,
                args.id,
                folder / f"{stem}.pvd",
                start=args.start,
                end=args.end,
                steps=args.steps,
                convention=args.convention,
                progress=moved,
            )
    if args.gif:
        from tgsis import pictures

        shown = [(t, [surface]) for t, surface in written.frames if surface is not None]
        first = shown[0][1][0] if shown else None
        same = first is not None and all(s[0].vertices.shape == first.vertices.shape for _, s in shown)
        pictures.animation(
            shown,
            args.gif,
            title=f"feature {args.id} ({fc.name})",
            time_unit=fc.time_unit or "",
            reference=[first] if same and first is not None else None,
            colour_label=f"moved since t = {shown[0][0]!r} (m)" if shown else "",
        )
    return render(args, WrittenFrames(args.id, fc, written, args.gif), series_text, series_json)


def series_text(args: argparse.Namespace, result: WrittenFrames) -> None:
    written, fc = result.written, result.fc
    times = [t for t, _ in written.frames]
    print_table(
        args,
        ("t", "file", "vertices", "triangles"),
        [
            (
                show_time(t),
                file,
                *((surface.n_vertices, surface.n_cells) if surface else ("no object (empty grid)", "")),
            )
            for (t, surface), file in zip(written.frames, written.files)
        ],
    )
    missing = f", {len(written.missing)} without the object" if written.missing else ""
    out(
        f"wrote {written.pvd}: feature {result.id} ({fc.name}) at {len(times)} times from "
        f"{show_time(times[0])} to {show_time(times[-1])}{time_unit_suffix(fc)}{missing}"
    )
    if result.gif:
        out(f"drew {len(times)} frames to {result.gif}")


def series_json(result: WrittenFrames) -> dict[str, Any]:
    written, fc = result.written, result.fc
    return {
        "pvd": str(written.pvd),
        "feature_id": result.id,
        "class": fc.name,
        "time_unit": fc.time_unit,
        "frames": [
            {
                "t": t,
                "file": str(file),
                "vertices": surface.n_vertices if surface else None,
                "triangles": surface.n_cells if surface else None,
            }
            for (t, surface), file in zip(written.frames, written.files)
        ],
        "missing": len(written.missing),
        "gif": result.gif,
    }


def add_at_parser(commands: Any) -> None:
    """``tgsis at``."""
    at = add_command(
        commands,
        "at",
        "write the surface of a feature at model time T to a file",
        ["tgsis at 12 -7.5 fault_7.5Ma.ts", "tgsis at 13 1.5 horizon.vtu --convention right"],
        cmd_at,
    )
    at.add_argument("id", type=FEATURE_ID, help="the feature's id")
    at.add_argument("time", type=float, metavar="T", help="model time (in the class's unit)")
    at.add_argument(
        "file",
        help="the file to write; its extension gives the format; {t} in it is replaced by T; "
        "a folder gets feature_ID_tT.FORMAT (with --format)",
    )
    at.add_argument("--format", help="file format (default: from the extension)")
    at.add_argument(
        "--convention",
        type=str.lower,
        choices=("left", "right"),
        default="left",
        help="step convention of a surface known at instants (default: left)",
    )
    at.add_argument(
        "--png",
        metavar="PNG",
        help="also draw the surface at T to this PNG file, coloured by how far it moved since its first instant",
    )
    at.add_argument(
        "--with",
        dest="with_ids",
        type=FEATURE_ID,
        nargs="+",
        default=[],
        metavar="ID",
        help="with --png: other features drawn at T in the same scene (the structure at T)",
    )


def add_series_parser(commands: Any) -> None:
    """``tgsis series``."""
    series = add_command(
        commands,
        "series",
        "write a feature over model time as a ParaView .pvd time series",
        [
            "tgsis series 12 out --from -10 --to 0 --steps 101",
            "tgsis series 12 out --name fault_history",
            "tgsis series 12 out --json",
        ],
        cmd_series,
        tabular=True,
    )
    series.add_argument("id", type=FEATURE_ID, help="the feature's id")
    series.add_argument("dir", metavar="DIR", help="folder of the .pvd and its frames (created if missing)")
    series.add_argument("--from", dest="start", type=float, metavar="T0", help="first time")
    series.add_argument("--to", dest="end", type=float, metavar="T1", help="last time")
    series.add_argument(
        "--steps",
        type=INT4,
        metavar="N",
        help="N frames evenly spaced from T0 to T1, both included (without --from/--to/--steps: "
        "one frame at each of the feature's own instants)",
    )
    series.add_argument("--name", help="name of the .pvd file (default: feature_ID)")
    series.add_argument(
        "--convention",
        type=str.lower,
        choices=("left", "right"),
        default="left",
        help="step convention of a surface known at instants (default: left)",
    )
    series.add_argument(
        "--gif",
        metavar="GIF",
        help="also draw the frames as an animated GIF, coloured by how far the surface moved since the first frame",
    )


def add_query_parser(commands: Any) -> None:
    """``tgsis query``."""
    query = add_command(
        commands,
        "query",
        "the features of a temporal class whose per-instant property satisfies PROPERTY OP VALUE, and when",
        [
            "tgsis query faults throw '>=' 100 --first   # when each fault's throw first reaches 100",
            "tgsis query faults throw '<' 5 --json",
        ],
        cmd_query,
        tabular=True,
    )
    query.add_argument("feature_class", metavar="CLASS", help="an INSTANTS or EVOLVING feature class")
    query.add_argument("property", metavar="PROPERTY", help="a numeric per-instant property of the class")
    query.add_argument("op", metavar="OP", choices=("<", "<=", "=", "<>", ">=", ">"), help="one of < <= = <> >= >")
    query.add_argument("value", metavar="VALUE", type=float, help="the number compared with (-inf, inf allowed)")
    query.add_argument("--first", action="store_true", help="only when the condition first holds, per feature")
    query.add_argument(
        "--convention",
        type=str.lower,
        choices=("left", "right"),
        default="left",
        help="step convention of features known at instants (default: left)",
    )
