"""``tgsis checkout`` and ``tgsis checkin``: edit a feature in any tool."""

from __future__ import annotations

import argparse
import math
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tgsis.cli._arguments import FEATURE_ID, add_command, feature_values
from tgsis.cli._connection import connection, require_this_build
from tgsis.cli._output import out, render
from tgsis.cli._progress import busy
from tgsis.db import versions as V
from tgsis.db.checkin import CheckinResult
from tgsis.db.connect import connect
from tgsis.errors import (
    InvalidInputError,
    NotFoundError,
)
from tgsis.mesh import Surface

# --------------------------------------------------------------------------- check-out / check-in


def _checkout_file(path: str) -> Path:
    """Where ``tgsis checkout`` keeps the token and base of the mesh it wrote to ``path``."""
    return Path(f"{path}.tgsis-checkout.npz")


def cmd_checkout(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.db.checkin import checkout

    with connection(args) as conn, busy(f"downloading feature {args.id}"):
        co = checkout(conn, args.id, args.feature_class)
    formats.write(co.mesh, args.file, format=args.format)
    written = formats.read_one(args.file, format=args.format)
    if not np.array_equal(written.vertices, co.mesh.vertices):  # the format must keep every bit of the base
        raise InvalidInputError(
            f"{args.file}: the format does not keep the coordinates exactly, so a check-in "
            "would see every vertex as moved",
            hint="use .ts (GOCAD) or .vtu (VTK)",
        )
    side = co.save(_checkout_file(args.file))
    out(
        f"checked out feature {co.token.feature_id} ({co.token.feature_class}, {co.mesh.n_vertices} vertices, "
        f"{co.mesh.n_cells} {type(co.mesh).cell_name}s) of version {V.show_name(co.token.version)} at revision "
        f"{co.token.revision} to {args.file} (check-out record: {side})"
    )
    return 0


def cmd_checkin(args: argparse.Namespace) -> int:
    from tgsis import formats
    from tgsis.db.checkin import Checkout, checkin

    side = _checkout_file(args.file)
    if not side.is_file():
        raise NotFoundError(
            f"{args.file} was not checked out here: {side} is missing",
            hint="tgsis checkout ID FILE writes the file and its check-out record",
        )
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise InvalidInputError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    co = Checkout.load(side)
    edited = formats.read_one(args.file, format=args.format)
    if args.png and not isinstance(edited, Surface):  # refused before anything is checked in
        raise InvalidInputError(f"{args.file} holds a {type(edited).__name__}: --png draws surfaces")
    with (
        connect(args.dsn) as conn,
        busy("checking in"),
    ):  # the check-out's version, whatever version commands work in now
        require_this_build(conn)
        result = checkin(
            conn,
            co,
            edited,
            feature_values(args.set) or None,
            name=args.name,
            tolerance=args.tolerance,
            on_conflict=args.on_conflict,
            child_version=args.child_version,
            keep=not args.no_keep,
            drop_extra_properties=args.drop_extra_properties,
        )
    save = result.save
    if result.checkout is not None and not result.conflict:  # before anything is printed (a reader may go away)
        result.checkout.save(side)
    child = shlex.quote(save.version)  # the commands are pasted into a shell: a free-text name stays one argument
    commands = (
        [
            f"tgsis version conflicts {child} --rows",
            f"tgsis version resolve {child} feature {save.feature_id} parent|child|manual",
            f"tgsis version merge {child} --remove",
        ]
        if result.conflict and not result.merged
        else []
    )
    if args.png and isinstance(edited, Surface):
        from scipy.spatial import cKDTree

        from tgsis import pictures

        # how far each vertex lies from the checked-out shape: 0 for the ones kept
        distance = cKDTree(co.mesh.vertices).query(edited.vertices)[0]
        distance[save.diff.vertex_map >= 0] = 0.0
        pictures.scene(
            [edited],
            args.png,
            colour=[distance],
            colour_label="moved from the check-out (m)",
            title=f"feature {save.feature_id} checked in to {save.version}",
        )
    record = side if result.checkout is not None and not result.conflict else None
    checked = CheckedIn(result, type(edited).cell_name, record, args.png, commands)
    return render(args, checked, checkin_text, checkin_json)


@dataclass(frozen=True)
class CheckedIn:
    """What a check-in did; ``record``: the check-out record kept for the next check-in (None: none), ``commands``:
    what settles the conflict when the edit went into a child version."""

    result: CheckinResult
    cell_name: str
    record: Path | None
    png: str | None
    commands: list[str]


def checkin_text(args: argparse.Namespace, checked: CheckedIn) -> None:
    result, save = checked.result, checked.result.save
    counts = save.diff.counts()
    moved = save.vertices_moved
    out(
        f"checked in feature {save.feature_id} into version {V.show_name(save.version)}"
        + (
            " (merged by region with the change made since check-out; check out again to go on editing)"
            if result.merged
            else " (a new child version: the feature had changed since check-out)"
            if result.conflict
            else ""
        )
    )
    out(
        f"  vertices: {counts['vertices_kept']} kept, {moved} moved, "
        f"{counts['vertices_removed'] - moved} removed, {counts['vertices_added'] - moved} "
        f"added; {checked.cell_name}s: {counts['cells_kept'] + save.cells_on_moved} kept"
        + (f" ({save.cells_on_moved} of them on moved vertices)" if save.cells_on_moved else "")
        + f", {save.cells_removed} removed, {save.cells_added} added"
    )  # by content, as they are stored
    out(
        f"  rows written: {save.rows_written} ({save.rows_deleted} deleted, {save.rows_inserted} inserted, "
        f"{save.rows_updated} updated)"
    )
    if result.not_applied:
        out(
            f"  not applied: the file's {', '.join(result.not_applied)} (the merge merges the mesh and keeps the "
            "stored ones; check out again and check in the change alone to apply them)"
        )
    if checked.png:
        out(f"  drew the edit to {checked.png}")
    if checked.commands:
        out(f"  both edits meet as a conflict of {V.show_name(save.version)}: " + "; ".join(checked.commands))


def checkin_json(checked: CheckedIn) -> dict[str, Any]:
    result, save = checked.result, checked.result.save
    counts = save.diff.counts()
    moved = save.vertices_moved
    return {
        "feature_id": save.feature_id,
        "version": save.version,
        "conflict": result.conflict,
        "merged": result.merged,
        "not_applied": list(result.not_applied),
        "vertices": {
            "kept": counts["vertices_kept"],
            "moved": moved,
            "removed": counts["vertices_removed"] - moved,
            "added": counts["vertices_added"] - moved,
        },
        "cells": {
            "kept": counts["cells_kept"] + save.cells_on_moved,
            "removed": save.cells_removed,
            "added": save.cells_added,
            "on_moved_vertices": save.cells_on_moved,
        },
        "rows": {
            "written": save.rows_written,
            "deleted": save.rows_deleted,
            "inserted": save.rows_inserted,
            "updated": save.rows_updated,
        },
        "record": str(checked.record) if checked.record is not None else None,
        "png": checked.png,
        "commands": checked.commands,
    }


def add_checkout_parser(commands: Any) -> None:
    """``tgsis checkout``."""
    co = add_command(
        commands,
        "checkout",
        "write a feature to a file for editing, recording what it was",
        ["tgsis checkout 42 fault.ts   # edit fault.ts in any tool, then: tgsis checkin fault.ts"],
        cmd_checkout,
    )
    co.add_argument("id", type=FEATURE_ID, help="the feature's id")
    co.add_argument("file", help="the file to edit (.ts, .vtk, .vtu, ...); the record goes to FILE.tgsis-checkout.npz")
    co.add_argument("--class", dest="feature_class", help="its feature class (default: looked up)")
    co.add_argument("--format", help="file format (default: from the extension)")


def add_checkin_parser(commands: Any) -> None:
    """``tgsis checkin``."""
    ci = add_command(
        commands,
        "checkin",
        "write an edited file back by difference, unless the feature changed since check-out",
        ["tgsis checkin fault.ts", "tgsis checkin fault.ts --tolerance 0.01 --on-conflict child --json"],
        cmd_checkin,
        tabular=False,
    )
    ci.add_argument("file", help="a file written by tgsis checkout, edited")
    ci.add_argument("--format", help="file format (default: from the extension)")
    ci.add_argument(
        "--tolerance",
        type=float,
        default=0.0,
        metavar="T",
        help="vertices within distance T of a checked-out vertex are unchanged (default 0: equal coordinates)",
    )
    ci.add_argument(
        "--on-conflict",
        choices=("raise", "child", "merge"),
        default="raise",
        help="when the feature changed since check-out: fail (default), write the edit into a new child version, "
        "or merge it with that change by region (refused, nothing written, where both changed the same part)",
    )
    ci.add_argument("--child-version", metavar="NAME", help="name of that child version (default checkin_ID)")
    ci.add_argument("--name", help="new feature name")
    ci.add_argument("--set", action="append", metavar="NAME=VALUE", help="a feature property value (repeatable)")
    ci.add_argument(
        "--drop-extra-properties",
        action="store_true",
        help="ignore properties of the file that the class does not store",
    )
    ci.add_argument(
        "--no-keep",
        dest="no_keep",
        action="store_true",
        help="do not update the check-out record (by default it follows the new state, so that the "
        "file can be edited and checked in again)",
    )
    ci.add_argument(
        "--png",
        metavar="PNG",
        help="also draw the edited surface, coloured by how far each vertex lies "
        "from the checked-out shape (0 for the kept ones)",
    )
