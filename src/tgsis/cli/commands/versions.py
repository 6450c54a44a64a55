"""``tgsis version`` and ``tgsis versioning``: versions (long transactions), versioned tables."""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import psycopg

from tgsis.cli._arguments import INT4, add_command
from tgsis.cli._connection import connection, split_version, target_key
from tgsis.cli._output import out, print_table, render, show_moment
from tgsis.cli._progress import busy, progress
from tgsis.cli._render import ObjectDifference, summarize_differences
from tgsis.cli._state import remember_version, remembered_version
from tgsis.db import regions as R
from tgsis.db import versions as V
from tgsis.db.connect import connect
from tgsis.db.features import (
    class_of_feature,
    fetch_feature,
)
from tgsis.db.inspect import revision_exists
from tgsis.db.merging import (
    MergeResult,
    export_conflict,
    merge_regions_json,
    merge_version,
    object_merge,
    refresh_version,
)
from tgsis.errors import (
    InvalidInputError,
    MissingPrivilegeError,
    NotFoundError,
    VersioningError,
)
from tgsis.merge3 import MergeRegion, MeshMerge
from tgsis.mesh import GeometryCollection, Mesh, Surface

# --------------------------------------------------------------------------- versions


def cmd_version_create(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        revision = V.create_version(conn, args.name, args.parent, description=args.description)
    out(f"created version {V.show_name(args.name)} (parent {V.show_name(args.parent)}), working revision {revision}")
    return 0


@dataclass(frozen=True)
class VersionList:
    """The versions, and the one this command works in."""

    current: str | None
    versions: list[V.Version]


def cmd_version_list(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        versions = V.list_versions(conn)
        current = V.working_version(conn)
    return render(args, VersionList(current, versions), version_list_text, version_list_json)


def version_list_text(args: argparse.Namespace, result: VersionList) -> None:
    print_table(
        args,
        ("current", "version", "parent", "initrevision", "working", "owner", "created", "description"),
        [
            (
                "*" if v.name == result.current else "",
                v.name,
                v.parent or "-",
                v.initrevision if v.initrevision is not None else "-",
                v.workingrevision,
                v.owner,
                show_moment(v.created_at),
                v.description or "",
            )
            for v in result.versions
        ],
    )


def version_list_json(result: VersionList) -> dict[str, Any]:
    """Also ``tgsis version tree --json``'s: the versions depth-first, each after its parent."""
    return {"current": result.current, "versions": [_version_json(v, result.current) for v in result.versions]}


def _version_json(v: V.Version, current: str | None) -> dict[str, Any]:
    return {
        "name": v.name,
        "parent": v.parent,
        "depth": v.depth,
        "initrevision": v.initrevision,
        "working_revision": v.workingrevision,
        "revisions": list(v.revisions),
        "saved": [{"name": n, "revision": r} for n, r in sorted(v.saved.items(), key=lambda item: item[1])],
        "owner": v.owner,
        "created_at": v.created_at,
        "description": v.description,
        "current": v.name == current,
    }


def cmd_version_tree(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        versions = V.list_versions(conn)
        current = V.working_version(conn)
    return render(args, VersionList(current, versions), version_tree_text, version_list_json)


def version_tree_text(args: argparse.Namespace, result: VersionList) -> None:
    out(V.format_tree(result.versions))


def cmd_version_goto(args: argparse.Namespace) -> int:
    name, revision = split_version(args.name)
    with connect(args.dsn) as conn:
        if revision is None:
            V.goto_version(conn, name)  # checks that it exists
            working = V.working_revision(conn)
        else:
            V.goto_revision(conn, name, revision)
    remember_version(target_key(args), args.name)
    if revision is None:
        out(f"commands on this database now work in version {V.show_name(name)} (working revision {working})")
    else:
        out(f"commands on this database now look at revision {revision} of version {V.show_name(name)} (read-only)")
    return 0


@dataclass(frozen=True)
class CurrentVersion:
    """The version a command works in, the revision it looks at (None: the working one), where the choice came from."""

    version: str
    working: int
    viewing: int | None
    source: str


def cmd_version_current(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        name, working, viewing = V.working_version(conn), V.working_revision(conn), V.viewing_revision(conn)
    source = (
        "--in"
        if args.in_version
        else "$TGSIS_VERSION"
        if os.environ.get("TGSIS_VERSION")
        else "tgsis version goto"
        if remembered_version(target_key(args))
        else "default"
    )
    return render(args, CurrentVersion(name, working, viewing, source), current_version_text, current_version_json)


def current_version_text(args: argparse.Namespace, result: CurrentVersion) -> None:
    looking = f"\tviewing revision {result.viewing} (read-only)" if result.viewing is not None else ""
    out(f"{result.version}\tworking revision {result.working}{looking}\t(from {result.source})")


def current_version_json(result: CurrentVersion) -> dict[str, Any]:
    return {
        "version": result.version,
        "working_revision": result.working,
        "viewing_revision": result.viewing,
        "read_only": result.viewing is not None,
        "source": result.source,
    }


def cmd_version_save(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        saved = V.save_revision(conn, args.name)
        version, working = V.working_version(conn), V.working_revision(conn)
    out(f"saved revision {saved} of {V.show_name(version)} as {V.show_name(args.name)}; new working revision {working}")
    return 0


def cmd_version_delete(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        removed = V.delete_version(conn, args.name)
    if remembered_version(target_key(args)) == args.name:
        remember_version(target_key(args), None)
    out(f"deleted version {V.show_name(args.name)} and {removed} row version(s)")
    return 0


def _discards_json(discards: Sequence[V.Discard]) -> list[dict[str, Any]]:
    return [
        {
            "table": d.shortname,
            "what": d.description,
            "rows_added": d.rows_added,
            "rows_removed": d.rows_removed,
            "rows_changed": d.rows_changed,
            "values_changed": d.values_changed,
        }
        for d in discards
    ]


@dataclass(frozen=True)
class VersionConflicts:
    """The conflicts of a version with its parent; ``rows``: both sides' rows per object (``--rows``);
    ``lost``: what each solution discards per (class, key, solution), None when this role may not read it."""

    version: str
    conflicts: list[V.Conflict]
    with_rows: bool
    rows: dict[tuple[str, str], list[tuple[str, str, Any, Any]]]
    lost: dict[tuple[str, str, str], list[V.Discard]] | None
    #: ``--regions``: per (class, key), the object's three-way merge, or why it merges as a whole object only
    regions: dict[tuple[str, str], MeshMerge | str] = field(default_factory=dict)
    #: ``--export``: per (class, key), the files written, or why none was
    exported: dict[tuple[str, str], list[Path] | str] = field(default_factory=dict)


def _object_regions(conn: Any, version: str, conflicts: Sequence[V.Conflict]) -> dict[tuple[str, str], MeshMerge | str]:
    """The three-way merge of each conflicting model-1 feature (read in one snapshot each), or why there is none.

    A role that may not read an object's class gets the permission error: no partial answer.
    """
    if conn.info.transaction_status != psycopg.pq.TransactionStatus.IDLE:
        conn.commit()  # find_conflicts' own transaction is over; object_merge reads in a snapshot of its own
    found: dict[tuple[str, str], MeshMerge | str] = {}
    for c in conflicts:
        key = (c.objectclass, c.objectkey)
        if c.objectclass != "feature":
            found[key] = f"whole object: a row of {c.objectclass}, not a mesh"
            continue
        sliced = sorted({r.times for r in c.regions if r.times is not None})
        if sliced:  # models 2 and 3: found and listed per instant by find_conflicts
            found[key] = (
                f"by instant: {len(c.regions)} regions at {len(sliced)} instant(s) "
                f"({', '.join(f'{t:.17g}' for t in sliced[:8])}{', ...' if len(sliced) > 8 else ''}); "
                "--json lists them (conflict_regions, each with its times)"
            )
            continue
        try:
            found[key] = object_merge(conn, version, int(c.objectkey))
        except InvalidInputError as exc:  # not a mesh of model 1, or states that do not compare (other columns)
            # find_conflicts' own reason first: a model-2/3 object refused there is not "of another model"
            found[key] = f"whole object: {c.region_refusal or exc.message}"
        except VersioningError as exc:  # changed on one side only by now (another session's merge or refresh)
            found[key] = f"no merge: {exc.message}"
    return found


def _region_text(region: MergeRegion) -> str:
    low, high = region.bounds
    how = (
        "conflict" if region.conflict else ("merges (same rows on both sides)" if region.sides == "both" else "merges")
    )
    return (
        f"\tregion {region.index}\t{how}\tchanged in {region.sides}"
        f"\tvertices {len(region.parent_vertex_ids)} parent, {len(region.child_vertex_ids)} child, "
        f"{len(region.vertex_ids)} in all"
        f"\tcells {len(region.parent_cell_ids)} parent, {len(region.child_cell_ids)} child, {len(region.cell_ids)} in all"
        f"\tbox {' '.join(f'{v:.17g}' for v in low)} .. {' '.join(f'{v:.17g}' for v in high)}"
        f"\tlargest displacement {region.parent_displacement:.17g} parent, {region.child_displacement:.17g} child"
    )


def _export_conflicts(
    conn: Any, args: argparse.Namespace, conflicts: Sequence[V.Conflict]
) -> dict[tuple[str, str], list[Path] | str]:
    """``--export DIR``: each conflicting mesh's three states, regions and picture, or why none is written.

    Every object is written into a scratch folder inside DIR first; the files are moved into DIR only when
    all are written and (without ``--force``) no name is taken, so a refusal leaves DIR as it was.
    """
    import shutil
    import tempfile

    from tgsis._optional import require
    from tgsis.errors import InstallationError

    if conn.info.transaction_status != psycopg.pq.TransactionStatus.IDLE:
        conn.commit()  # find_conflicts' own transaction is over; each export reads in a snapshot of its own
    try:
        require("matplotlib", "the PNG overlays")
        picture = True
    except InstallationError as exc:
        picture = False
        print(f"tgsis: notice: no PNG overlays: {exc.message} ({exc.hint})", file=sys.stderr)
    _check_export_format(args.format)
    folder = Path(args.export)
    made = [p for p in (folder, *folder.parents) if not p.exists()]  # removed again when the export is refused
    folder.mkdir(parents=True, exist_ok=True)
    done: dict[tuple[str, str], list[Path] | str] = {}
    scratch = Path(tempfile.mkdtemp(prefix=".tgsis-export-", dir=folder))
    refused = True
    try:
        for c in conflicts:
            key = (c.objectclass, c.objectkey)
            if c.objectclass != "feature":
                done[key] = f"no files: a row of {c.objectclass}, not a mesh"
                continue
            try:
                done[key] = export_conflict(
                    conn, args.name, int(c.objectkey), scratch, format=args.format, picture=picture, overwrite=True
                )
            except (InvalidInputError, VersioningError) as exc:  # not a mesh of model 1; changed on one side only
                done[key] = f"no files: {exc.message}"
        written = [f for files in done.values() if not isinstance(files, str) for f in files]
        there = [f.name for f in written if (folder / f.name).exists()]
        if there and not args.force:
            raise InvalidInputError(
                f"{len(there)} file(s) already in {folder}: {', '.join(there)}; nothing was written",
                hint="remove them, choose another --export folder, or add --force to replace them",
            )
        refused = False
        for f in written:
            os.replace(f, folder / f.name)
        return {
            key: files if isinstance(files, str) else [folder / f.name for f in files] for key, files in done.items()
        }
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        if refused:
            for p in made:  # innermost first; a folder someone else filled meanwhile stays
                with contextlib.suppress(OSError):
                    p.rmdir()


def _check_export_format(ext: str | None) -> None:
    """Refuse ``--format`` before anything is made when no file format of tgsis writes that extension."""
    if ext is None:
        return
    from tgsis import formats

    try:
        kind = formats.format_for(f"x.{ext.lower().lstrip('.')}")
    except Exception:  # FileFormatError: unknown extension
        kind = None
    if kind is None or kind.writer is None:
        raise InvalidInputError(
            f"no file format has the extension {ext!r}",
            hint="give --format ts, pl, vs, so, vtu, vtp or ply (or leave it out: the GOCAD file of the object's kind)",
        )


def cmd_version_conflicts(args: argparse.Namespace) -> int:
    for flag in ("force", "format"):
        if getattr(args, flag, None) and not getattr(args, "export", None):
            raise InvalidInputError(f"--{flag} is for the exported files: it needs --export DIR")
    with connection(args) as conn:
        # region-aware: the regions of each conflicting mesh found (in one snapshot with the marks) and stored
        conflicts = R.find_conflicts(conn, args.name)
        exported = _export_conflicts(conn, args, conflicts) if getattr(args, "export", None) else {}
        regions = _object_regions(conn, args.name, conflicts) if getattr(args, "regions", False) else {}
        details = (
            {
                (c.objectclass, c.objectkey): V.conflict_rows(conn, args.name, c.objectclass, c.objectkey)
                for c in conflicts
            }
            if args.rows
            else {}
        )
        # what each solution would throw away of the other side's edits (until merges are three-way), read with
        # this role's rights: one that may not read some of the objects' rows still gets the list, without it
        lost: dict[tuple[str, str, str], list[V.Discard]] | None = None
        try:
            with conn.transaction():
                discards = V.conflict_discards(conn, args.name) if conflicts else []
            lost = {}
            for d in discards:
                lost.setdefault((d.objectclass, d.objectkey, d.solution), []).append(d)
        except MissingPrivilegeError as exc:
            print(f"tgsis: warning: what each solution discards is not shown: {exc.message}", file=sys.stderr)
            lost = None
    result = VersionConflicts(args.name, conflicts, args.rows, details, lost, regions, exported)
    if not getattr(args, "json", False):
        for (objectclass, objectkey), files in exported.items():
            if isinstance(files, str):
                out(f"{objectclass} {objectkey}: {files}")
            else:
                for f in files:
                    out(f"wrote {f}")
    return render(args, result, conflicts_text, conflicts_json)


def conflicts_text(args: argparse.Namespace, result: VersionConflicts) -> None:
    conflicts, lost = result.conflicts, result.lost
    if conflicts and not getattr(args, "no_header", False):
        out(
            "class\tkey\tsolution\tboth changed\tchanged in "
            + result.version
            + "\tchanged in parent"
            + "\tchild discards (the parent's edits)\tparent discards (the version's edits)"
            + ("\n\ttable\tside\trow key (JSON)\trow (JSON)" if result.with_rows else "")
        )
    for c in conflicts:
        both = ", ".join(c.conflicttype) or "different tables"
        said = [
            "?"
            if lost is None
            else "; ".join(d.summary() for d in lost.get((c.objectclass, c.objectkey, solution), [])) or "nothing"
            for solution in ("child", "parent")
        ]
        out(
            f"{c.objectclass}\t{c.objectkey}\t{c.solution}\t{both}\t"
            f"{', '.join(c.childtables)}\t{', '.join(c.parenttables)}\t{said[0]}\t{said[1]}"
        )
        for table, side, key, row in result.rows.get((c.objectclass, c.objectkey), []):
            out(f"\t{table}\t{side}\t{json.dumps(key)}\t{json.dumps(row)}")
        merge = result.regions.get((c.objectclass, c.objectkey))
        if isinstance(merge, str):
            out(f"\tregions\t{merge}")
        elif merge is not None:
            conflicting = len(merge.conflicts)
            out(
                f"\tregions\t{len(merge.regions)} region(s), {conflicting} in conflict: "
                + (
                    "the object merges by itself"
                    if not conflicting
                    else "those need a solution, the others merge by themselves"
                )
            )
            # the solution stored for the same region (same ids), as find_conflicts left it
            recorded = {r.region: r for r in c.regions}
            for region in merge.regions:
                stored = recorded.get(region.index)
                same = (
                    stored is not None
                    and np.array_equal(stored.vertex_ids, region.vertex_ids)
                    and np.array_equal(stored.cell_ids, region.cell_ids)
                )
                out(_region_text(region) + (f"\tsolution {stored.solution}" if same and stored else ""))
    if not conflicts:
        print(f"version {V.show_name(result.version)} has no conflicts with its parent", file=sys.stderr)


def conflicts_json(result: VersionConflicts) -> dict[str, Any]:
    lost = result.lost
    return {
        "version": result.version,
        "conflicts": [
            {
                "objectclass": c.objectclass,
                "objectkey": c.objectkey,
                "solution": c.solution,
                "both_changed": list(c.conflicttype),
                "child_tables": list(c.childtables),
                "parent_tables": list(c.parenttables),
                "discards": None
                if lost is None
                else {
                    solution: {"edits_of": other, "tables": _discards_json(lost.get(key + (solution,), []))}
                    for key in [(c.objectclass, c.objectkey)]
                    for solution, other in (("child", "parent"), ("parent", "child"))
                },
                **(
                    {
                        "rows": [
                            {"table": table, "side": side, "key": key, "row": row}
                            for table, side, key, row in result.rows.get((c.objectclass, c.objectkey), [])
                        ]
                    }
                    if result.with_rows
                    else {}
                ),
                # the stored regions of a mesh with their solutions (tgsis version resolve ... --region N)
                "conflict_regions": [r.as_json() for r in c.regions],
                "region_refusal": c.region_refusal,
                **(
                    {"regions": merge_regions_json(result.regions[(c.objectclass, c.objectkey)])}
                    if (c.objectclass, c.objectkey) in result.regions
                    else {}
                ),
                **(
                    {"exported": _exported_json(result.exported[(c.objectclass, c.objectkey)])}
                    if (c.objectclass, c.objectkey) in result.exported
                    else {}
                ),
            }
            for c in result.conflicts
        ],
    }


def _exported_json(files: list[Path] | str) -> dict[str, Any]:
    if isinstance(files, str):
        return {"files": [], "reason": files}
    return {"files": [str(f) for f in files]}


def _resolve_region(args: argparse.Namespace) -> int:
    """``--region N``: FEATURE SOLUTION (or feature FEATURE SOLUTION); what the solution discards is said first."""
    words = [w for w in (args.objectclass, args.objectkey, args.solution) if w is not None]
    if len(words) == 3:
        if words[0] != "feature":
            raise InvalidInputError(
                f"--region solves a region of a feature's mesh, not of an object of class {words[0]!r}",
                hint="give the feature's id and the solution: tgsis version resolve VERSION ID SOLUTION --region N",
            )
        words = words[1:]
    if len(words) != 2:
        raise InvalidInputError(
            "--region needs the feature's id and the solution",
            hint="tgsis version resolve VERSION ID parent|child|base|average|manual --region N [--mesh FILE] (every "
            "conflicting region at once: --region all)",
        )
    try:
        feature = int(words[0])
    except ValueError:
        raise InvalidInputError(
            f"feature {words[0]!r} is not a feature id",
            hint="give the feature's id (tgsis version conflicts VERSION lists them)",
        ) from None
    solution = words[1].lower()
    if args.region == "all":
        return _resolve_all_regions(args, feature, solution)
    mesh: Mesh | None = None
    if args.mesh is not None:
        if solution != "manual":
            raise InvalidInputError(
                f"--mesh is the region's rows of the solution manual, not of {solution}",
                hint="give manual with --mesh, or leave --mesh out",
            )
        from tgsis import formats

        mesh = formats.read_one(args.mesh)
    elif solution == "manual":
        raise InvalidInputError(
            "the solution manual needs the region's mesh",
            hint="give --mesh FILE: e.g. the child file of tgsis version conflicts VERSION --export DIR, edited "
            "(its vertex property vrtxid keeps the ids)",
        )
    with connection(args) as conn:
        result = R.resolve_region(
            conn, args.name, feature, int(args.region), solution, mesh, discard_other=args.discard_other
        )
    for discard in result.discards:
        out(f"  {R.discard_text(discard)}")
    out(
        f"feature {feature} in {V.show_name(args.name)}: region {result.region.region} recorded {result.region.solution}"
    )
    return 0


def _resolve_all_regions(args: argparse.Namespace, feature: int, solution: str) -> int:
    """``--region all``: one solution for every conflicting region of the feature; the sums said first."""
    if solution == "manual" or args.mesh is not None:
        raise InvalidInputError(
            "--region all takes parent, child, base, average or unsolved, without --mesh: manual is a region's "
            "(its mesh holds the region's rows)",
            hint="tgsis version resolve VERSION ID manual --region N --mesh FILE",
        )
    with connection(args) as conn:
        result = R.resolve_all_regions(conn, args.name, feature, solution, discard_other=args.discard_other)
    for total in result.totals:
        out(f"  {R.side_discard_text(total)}")
    for discard in result.discards:
        out(f"  {R.discard_text(discard)}")
    recorded = ", ".join(str(r.region) for r in result.regions)
    out(f"feature {feature} in {V.show_name(args.name)}: regions {recorded} recorded {solution}")
    return 0


def _region_argument(value: str) -> int | str:
    """``--region``: a region's index, or ``all`` (every conflicting region of the feature)."""
    if value.strip().lower() == "all":
        return "all"
    try:
        index = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{value!r} is no region: give its index N or all") from None
    return index


def cmd_version_resolve(args: argparse.Namespace) -> int:
    if args.region is not None:
        return _resolve_region(args)
    if args.mesh is not None:
        raise InvalidInputError("--mesh is for a region's manual solution: it needs --region N")
    if args.solution is None or args.solution not in ("parent", "child", "base", "average", "manual", "unsolved"):
        raise InvalidInputError(
            f"solution {args.solution!r} of an object is not parent, child, base, average, manual or unsolved"
            if args.solution is not None
            else "the solution is missing",
            hint="tgsis version resolve VERSION CLASS KEY parent|child|base|average|manual|unsolved (a region: "
            "--region N)",
        )
    with connection(args) as conn:
        c = R.resolve_conflict(
            conn, args.name, args.objectclass, args.objectkey, args.solution, discard_other=args.discard_other
        )
    if args.solution in ("base", "average"):  # written into the version, recorded manual
        for d in c.region_discards:
            out(f"  {R.discard_text(d)}")
        out(
            f"{c.objectclass} {c.objectkey} in {V.show_name(args.name)}: {args.solution} written into the version, "
            f"recorded {c.solution}"
        )
    else:
        out(f"{c.objectclass} {c.objectkey} in {V.show_name(args.name)}: {c.solution}")
    if c.discarded is None:
        out("  what it discarded of the other side's edits is not shown: this role may not read the object's rows")
    elif c.discarded:
        out(f"  discarded {V.describe_discards(c.discarded)}")
    return 0


def _recorded_discards(conn: Any, version: str) -> dict[tuple[str, str], tuple[str, list[V.Discard]]] | None:
    """What the recorded solutions discard, or None when this role may not read some of the objects' rows."""
    try:
        with conn.transaction():
            return V.recorded_discards(conn, version)
    except MissingPrivilegeError:
        return None


def _say_discarded(lost: dict[tuple[str, str], tuple[str, list[V.Discard]]] | None) -> None:
    if lost is None:
        out(
            "  what the solutions discarded of the other side's edits is not shown: this role may not read "
            "some of the objects' rows"
        )
        return
    for (objectclass, objectkey), (solution, discards) in lost.items():
        out(f"  {objectclass} {objectkey} ({solution}): discarded {V.describe_discards(discards)}")


def _copied(result: MergeResult) -> str:
    """What the SQL merge or refresh wrote, each unit apart: chunk versions (model 1 in chunks) only when some."""
    rows = f"{result.rows_copied} row(s)"
    if result.chunk_versions_copied:
        return f"{result.chunk_versions_copied} chunk version(s) and {rows}"
    return rows


def _say_merged_by_region(result: MergeResult) -> None:
    for o in result.objects:
        how = "every region merged by itself" if o.how == "automatic" else f"{o.solved} region(s) by their solutions"
        out(
            f"  {o.objectclass} {o.objectkey} merged by region ({o.regions} region(s), {how}): "
            f"{o.rows_written} row(s) written into the version"
        )
        for d in o.discards:
            out(
                f"    region {d.region} ({d.solution}) discarded the {d.side}'s edit there: {d.vertices} vertices, "
                f"{d.cells} cells, largest displacement {d.max_displacement:.6g}"
            )


def cmd_version_merge(args: argparse.Namespace) -> int:
    with connection(args) as conn, busy(f"merging {V.show_name(args.name)}"), conn.transaction():
        # what the recorded solutions throw away, read in the merge's transaction (a change since unsolves them)
        lost = _recorded_discards(conn, args.name)
        written = merge_version(conn, args.name, remove=args.remove)
    out(
        f"merged {V.show_name(args.name)} into its parent: {_copied(written)} written"
        + ("; version removed" if args.remove else "")
    )
    _say_merged_by_region(written)
    _say_discarded(lost)
    if args.remove and remembered_version(target_key(args)) == args.name:
        remember_version(target_key(args), None)
    return 0


def cmd_version_refresh(args: argparse.Namespace) -> int:
    with connection(args) as conn, conn.transaction():
        lost = _recorded_discards(conn, args.name)
        written = refresh_version(conn, args.name)
    out(f"refreshed {V.show_name(args.name)} from its parent: {_copied(written)} written")
    _say_merged_by_region(written)
    _say_discarded(lost)
    return 0


def _feature_as(conn: Any, fid: int, version: str, revision: int | None) -> Mesh | GeometryCollection | None:
    """Feature ``fid`` as a version (at a revision) sees it, or None where it does not exist there."""
    context = V.at_revision(conn, revision, version) if revision is not None else V.in_version(conn, version)
    with context:
        try:
            return fetch_feature(conn, class_of_feature(conn, fid), fid).mesh
        except NotFoundError:
            return None
        finally:
            conn.rollback()


def _draw_differences(
    conn: Any,
    args: argparse.Namespace,
    differences: Sequence[Any],
    sides: tuple[tuple[str, int | None], tuple[str, int | None]],
) -> None:
    """One PNG per changed surface feature: the new side coloured by how far each vertex moved, or both sides."""
    from tgsis import pictures

    folder = Path(args.png)
    folder.mkdir(parents=True, exist_ok=True)
    for fid in sorted({int(d.objectkey) for d in differences if d.objectclass == "feature"}):
        old, new = (_feature_as(conn, fid, version, revision) for version, revision in sides)
        shown = [m for m in (old, new) if isinstance(m, Surface)]
        if not shown:
            continue
        path = folder / f"diff_{fid}.png"
        title = f"feature {fid}: {args.a} -> {args.b}"
        if isinstance(old, Surface) and isinstance(new, Surface) and old.vertices.shape == new.vertices.shape:
            pictures.scene(
                [new],
                path,
                title=title,
                colour=[pictures.displacement(new, old)],
                colour_label=f"moved from {args.a} (m)",
            )
        else:
            if isinstance(old, Surface):
                old.name = f"{old.name or fid} in {args.a}"
            if isinstance(new, Surface):
                new.name = f"{new.name or fid} in {args.b}"
            pictures.scene(shown, path, title=title)
        out(f"drew feature {fid} to {path}")


def _object_order(key: tuple[str, str]) -> tuple[str, int, int, str]:
    """Objects by class, then numeric keys (feature ids) by number before other keys by text."""
    objectclass, objectkey = key
    return (
        (objectclass, 0, int(objectkey), "")
        if objectkey.isascii() and objectkey.isdigit()
        else (objectclass, 1, 0, objectkey)
    )


@dataclass(frozen=True)
class VersionDiff:
    """What differs from ``a`` to ``b`` (as the user named them): per object (``objects``, in key order) and per
    object and table (``differences``); ``per_table``: ``--tables`` shows the latter."""

    a: str
    b: str
    differences: list[V.Difference]
    objects: list[ObjectDifference]
    per_table: bool = False


def cmd_version_diff(args: argparse.Namespace) -> int:
    a, a_rev = split_version(args.a)
    b, b_rev = split_version(args.b)
    with connection(args) as conn:
        with progress(f"comparing {args.a} and {args.b}", None, "table") as moved:
            differences = V.diff_versions(conn, a, b, a_revision=a_rev, b_revision=b_rev, progress=moved)
        if args.png:
            _draw_differences(conn, args, differences, ((a, a_rev), (b, b_rev)))
    objects = summarize_differences(differences, args.a, args.b)
    objects.sort(key=lambda o: _object_order((o.objectclass, o.objectkey)))
    return render(args, VersionDiff(args.a, args.b, differences, objects, args.tables), diff_text, diff_json)


def diff_text(args: argparse.Namespace, result: VersionDiff) -> None:
    """A line per object (``--tables``: per object and table) on standard output, a summary on standard error."""
    differences, objects = result.differences, result.objects
    if result.per_table:
        print_table(
            args,
            ("class", "key", "table", "added", "removed", "changed"),
            [
                (d.objectclass, d.objectkey, d.table, f"+{d.added}", f"-{d.removed}", f"~{d.changed}")
                for d in differences
            ],
        )
    else:
        print_table(
            args,
            ("class", "key", "difference", "tables", "added", "removed", "changed"),
            [
                (
                    o.objectclass,
                    o.objectkey,
                    o.difference,
                    ",".join(o.tables),
                    f"+{o.added}",
                    f"-{o.removed}",
                    f"~{o.changed}",
                )
                for o in objects
            ],
        )
    if not differences:
        print(f"{result.a} and {result.b} hold the same rows", file=sys.stderr)
    elif not result.per_table:
        counts = {
            what: sum(o.difference == what for o in objects)
            for what in (f"only in {result.a}", f"only in {result.b}", "changed")
        }
        print(
            f"{len(objects)} object{'s' if len(objects) != 1 else ''} differ"
            f"{'s' if len(objects) == 1 else ''}: " + ", ".join(f"{n} {what}" for what, n in counts.items() if n),
            file=sys.stderr,
        )


def diff_json(result: VersionDiff) -> dict[str, Any]:
    return {
        "a": result.a,
        "b": result.b,
        "objects": [
            {
                "objectclass": o.objectclass,
                "objectkey": o.objectkey,
                "difference": o.difference,
                "tables": list(o.tables),
                "added": o.added,
                "removed": o.removed,
                "changed": o.changed,
            }
            for o in result.objects
        ],
        "differences": [
            {
                "objectclass": d.objectclass,
                "objectkey": d.objectkey,
                "table": d.table,
                "added": d.added,
                "removed": d.removed,
                "changed": d.changed,
            }
            for d in result.differences
        ],
    }


def _moment(text: str) -> datetime.datetime:
    try:
        moment = datetime.datetime.fromisoformat(text)
    except ValueError:
        raise InvalidInputError(
            f"{text!r} is not a date or time (ISO 8601, e.g. 2026-03-01 or 2026-03-01T12:00+01:00)"
        ) from None
    return moment if moment.tzinfo else moment.replace(tzinfo=datetime.timezone.utc)


def cmd_version_valid(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        V.set_version_validity(
            conn, args.name, _moment(args.valid_from), _moment(args.valid_to) if args.valid_to else None
        )
    out(
        f"version {V.show_name(args.name)} believed from {args.valid_from}"
        + (f" to {args.valid_to}" if args.valid_to else " on")
    )
    return 0


@dataclass(frozen=True)
class VersionBelieved:
    """The version of the chain below ``root`` believed true ``at`` a moment (None: none)."""

    at: datetime.datetime
    root: str
    version: str | None


@dataclass(frozen=True)
class VersionChain:
    """The versions below ``root`` with a validity period: (name, believed from, believed to or None)."""

    root: str
    chain: list[tuple[str, datetime.datetime, datetime.datetime | None]]


def cmd_version_chain(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        if args.at:
            at = _moment(args.at)
            believed = V.version_believed_at(conn, at, args.root)
            render(args, VersionBelieved(at, args.root, believed), believed_text, believed_json)
            return 0 if believed is not None else 3
        chain = V.version_chain(conn, args.root)
    return render(args, VersionChain(args.root, chain), chain_text, chain_json)


def believed_text(args: argparse.Namespace, result: VersionBelieved) -> None:
    out(result.version if result.version is not None else "-")


def believed_json(result: VersionBelieved) -> dict[str, Any]:
    return {"at": result.at, "root": result.root, "version": result.version}


def chain_text(args: argparse.Namespace, result: VersionChain) -> None:
    print_table(
        args,
        ("version", "believed from", "believed to"),
        [
            (name, show_moment(start), show_moment(end) if end else "still believed")
            for name, start, end in result.chain
        ],
    )


def chain_json(result: VersionChain) -> dict[str, Any]:
    return {
        "root": result.root,
        "chain": [{"version": name, "valid_from": start, "valid_to": end} for name, start, end in result.chain],
    }


def cmd_version_lock(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        taken = V.lock_objects(conn, args.name, args.objectclass, args.keys, exclusive=args.exclusive)
    out(
        f"{args.name} holds {len(set(args.keys))} {args.objectclass} object(s) ({taken} newly locked"
        + (", exclusive" if args.exclusive else "")
        + ")"
    )
    return 0


def cmd_version_unlock(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        released = V.unlock_objects(conn, args.name, args.objectclass, args.keys or None)
    out(f"released {released} lock(s) of {args.name}")
    return 0


@dataclass(frozen=True)
class ObjectLocks:
    """The object locks, of one version (``version``) or of all (None)."""

    version: str | None
    locks: list[V.ObjectLock]


def cmd_version_locks(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        locks = V.object_locks(conn, args.name)
    return render(args, ObjectLocks(args.name, locks), locks_text, locks_json)


def locks_text(args: argparse.Namespace, result: ObjectLocks) -> None:
    print_table(
        args,
        ("class", "key", "version", "role", "kind", "since"),
        [
            (
                lk.objectclass,
                lk.objectkey,
                lk.version,
                lk.locked_by,
                "exclusive" if lk.exclusive else "version",
                show_moment(lk.locked_at),
            )
            for lk in result.locks
        ],
    )
    if not result.locks:
        print("no object locks" + (f" in {result.version}" if result.version else ""), file=sys.stderr)


def locks_json(result: ObjectLocks) -> dict[str, Any]:
    return {
        "locks": [
            {
                "objectclass": lk.objectclass,
                "objectkey": lk.objectkey,
                "version": lk.version,
                "role": lk.locked_by,
                "exclusive": lk.exclusive,
                "since": lk.locked_at,
            }
            for lk in result.locks
        ]
    }


def cmd_version_grant(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        (V.revoke_version if args.revoke else V.grant_version)(conn, args.name, args.privilege, args.role)
    out(
        f"{'revoked' if args.revoke else 'granted'} {args.privilege} on {args.name} "
        f"{'from' if args.revoke else 'to'} {args.role}"
    )
    return 0


def cmd_version_owner(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        V.set_version_owner(conn, args.name, args.role)
    out(f"version {V.show_name(args.name)} is owned by {args.role}")
    return 0


@dataclass(frozen=True)
class VersionRights:
    """Owners by version, and the grants on them."""

    owners: dict[str, str]
    grants: list[V.VersionGrant]


def cmd_version_privileges(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        owners = {v.name: v.owner for v in V.list_versions(conn) if args.name in (None, v.name)}
        grants = V.version_privileges(conn, args.name)
    if args.name is not None and not owners:
        raise NotFoundError(f"version {args.name!r} does not exist")
    return render(args, VersionRights(owners, grants), privileges_text, privileges_json)


def privileges_text(args: argparse.Namespace, result: VersionRights) -> None:
    rows: list[tuple[str, ...]] = []
    for name, owner in result.owners.items():
        rows.append((name, owner, "owner (every right)"))
        rows += [(name, g.grantee, g.privilege, g.granted_by) for g in result.grants if g.version == name]
    print_table(args, ("version", "role", "right", "granted by"), rows)


def privileges_json(result: VersionRights) -> dict[str, Any]:
    return {
        "versions": [
            {
                "name": name,
                "owner": owner,
                "grants": [
                    {
                        "role": g.grantee,
                        "privilege": g.privilege,
                        "granted_by": g.granted_by,
                        "granted_at": g.granted_at,
                    }
                    for g in result.grants
                    if g.version == name
                ],
            }
            for name, owner in result.owners.items()
        ]
    }


@dataclass(frozen=True)
class Compression:
    """What compress removed (or would, ``dry_run``); ``forgotten``: the remembered revision it removed, if any."""

    dry_run: bool
    report: list[V.Compressed]
    forgotten: str | None
    looked_at: int | None

    @property
    def totals(self) -> dict[str, int]:
        return {
            what: sum(i.removed for i in self.report if i.what == what)
            for what in ("rows", "lastrevs", "revisions", "set entries")
        }


def cmd_version_compress(args: argparse.Namespace) -> int:
    remembered = remembered_version(target_key(args))
    looked_at = split_version(remembered)[1] if remembered else None
    with connect(args.dsn) as conn:
        report = V.compress_versions(conn, dry_run=args.dry_run)
        gone = looked_at is not None and not args.dry_run and not revision_exists(conn, looked_at)
    if gone:
        remember_version(target_key(args), None)
    result = Compression(args.dry_run, report, remembered if gone else None, looked_at)
    return render(args, result, compression_text, compression_json)


def compression_text(args: argparse.Namespace, result: Compression) -> None:
    report, totals = result.report, result.totals
    if report:
        print_table(args, ("what", "name", "removed"), [(item.what, item.name, item.removed) for item in report])
    summary = (
        f"{totals['rows']} row version(s), {totals['lastrevs']} lastrevs entr(ies), "
        f"{totals['revisions']} revision(s), {totals['set entries']} revision set entr(ies)"
    )
    if result.dry_run:
        out(
            f"compress would remove {summary} (dry run: nothing changed)"
            if report
            else "compress would remove nothing (dry run)"
        )
    else:
        out(f"compress removed {summary}" if report else "compress removed nothing")
    if result.forgotten is not None:
        out(
            f"revision {result.looked_at} is gone: commands on this database work in DEFAULT again "
            f"(was {result.forgotten})"
        )


def compression_json(result: Compression) -> dict[str, Any]:
    return {
        "dry_run": result.dry_run,
        "removed": [{"what": i.what, "name": i.name, "removed": i.removed} for i in result.report],
        "totals": result.totals,
        "forgotten": result.forgotten,
    }


def cmd_versioning_enable(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        if args.table == "features":
            count = V.enable_feature_versioning(conn)
            out(
                f"model 1 and the feature classes are versioned (object class feature): {count} table(s) newly versioned"
            )
            return 0
        if not (args.key and args.object_class):
            raise InvalidInputError(
                "versioning a table needs --key and --class",
                hint="e.g. tgsis versioning enable wells --key id --class well",
            )
        t = V.enable_versioning(conn, args.table, args.key, args.object_class, args.order, args.shortname)
        storage = V.storage_table(conn, t.schema, t.table)
    out(f"{t.schema}.{t.table} is versioned (object class {t.objectclass}, key {t.objectkeyfield}, storage {storage})")
    return 0


def cmd_versioning_disable(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        if args.table == "features":
            removed = V.disable_feature_versioning(conn, force=args.force)
        else:
            removed = V.disable_versioning(conn, args.table, force=args.force)
    out(f"{args.table}: versioning disabled, DEFAULT's rows kept, {removed} row version(s) removed")
    return 0


def cmd_versioning_list(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        tables = V.versioned_tables(conn)
    return render(args, tables, versioned_tables_text, versioned_tables_json)


def versioned_tables_text(args: argparse.Namespace, tables: list[V.VersionedTable]) -> None:
    print_table(
        args,
        ("table", "class", "key", "order", "shortname", "row key"),
        [
            (f"{t.schema}.{t.table}", t.objectclass, t.objectkeyfield, t.iudorder, t.shortname, ", ".join(t.keycolumns))
            for t in tables
        ],
    )
    if not tables:
        print("no versioned tables", file=sys.stderr)


def versioned_tables_json(tables: list[V.VersionedTable]) -> dict[str, Any]:
    return {
        "tables": [
            {
                "schema": t.schema,
                "table": t.table,
                "objectclass": t.objectclass,
                "key": t.objectkeyfield,
                "order": t.iudorder,
                "shortname": t.shortname,
                "row_key": list(t.keycolumns),
            }
            for t in tables
        ]
    }


def add_version_parser(commands: Any) -> None:
    """``tgsis version ACTION``."""
    ver = add_command(
        commands,
        "version",
        "versions (long transactions): create, goto, save, merge, lock, grant, ...",
        ["tgsis version create cfm6 && tgsis version goto cfm6"],
    )
    ver_commands = ver.add_subparsers(dest="version_command", metavar="ACTION", required=True)
    ver_create = add_command(
        ver_commands,
        "create",
        "create a child version",
        ["tgsis version create cfm6 --description 'release 6.1'"],
        cmd_version_create,
    )
    ver_create.add_argument("name", help="the new version's name")
    ver_create.add_argument("--parent", default="DEFAULT", help="parent version (default: DEFAULT)")
    ver_create.add_argument("--description", help="what the version is for, for people")
    add_command(
        ver_commands,
        "list",
        "list the versions (* marks the one commands work in)",
        ["tgsis version list", "tgsis version list --json"],
        cmd_version_list,
        tabular=True,
    )
    add_command(
        ver_commands,
        "tree",
        "print the version tree with revisions",
        ["tgsis version tree", "tgsis version tree --json"],
        cmd_version_tree,
        tabular=False,
    )
    ver_goto = add_command(
        ver_commands,
        "goto",
        "work in a version from now on (remembered per database)",
        [
            "tgsis version goto cfm6",
            "tgsis version goto cfm6@2   # look at revision 2, read-only",
            "tgsis version goto DEFAULT",
        ],
        cmd_version_goto,
    )
    ver_goto.add_argument(
        "name", metavar="VERSION[@REVISION]", help="a version, or a revision of its history to look at read-only"
    )
    add_command(
        ver_commands,
        "current",
        "the version commands work in, and its working revision",
        ["tgsis version current", "tgsis version current --json"],
        cmd_version_current,
        tabular=False,
    )
    ver_save = add_command(
        ver_commands,
        "save",
        "freeze the working revision under a name, start a new one",
        ["tgsis version save imported"],
        cmd_version_save,
    )
    ver_save.add_argument("name", help="the name of the saved revision")
    ver_delete = add_command(
        ver_commands,
        "delete",
        "delete a version without children, with its changes",
        ["tgsis version delete cfm6"],
        cmd_version_delete,
    )
    ver_delete.add_argument("name", help="the version to delete")

    ver_conflicts = add_command(
        ver_commands,
        "conflicts",
        "objects changed both in a version and in its parent",
        [
            "tgsis version conflicts cfm6",
            "tgsis version conflicts cfm6 --rows --json",
            "tgsis version conflicts cfm6 --regions",
            "tgsis version conflicts cfm6 --export conflicts/ --format vtu",
        ],
        cmd_version_conflicts,
        tabular=True,
    )
    ver_conflicts.add_argument("name", help="the child version (its parent is the other side)")
    ver_conflicts.add_argument("--rows", action="store_true", help="also print the rows that differ, per side")
    ver_conflicts.add_argument(
        "--regions",
        action="store_true",
        help="also merge each conflicting mesh (points, lines, surfaces, solids) three-way and print its regions: "
        "what each side changed, box, largest displacement, and which merge by themselves (docs/merge.md)",
    )
    ver_conflicts.add_argument(
        "--export",
        metavar="DIR",
        help="write each conflicting mesh's base, parent and child as files, its regions as JSON and a PNG "
        "overlay into DIR (made when missing); file vertex i is the i-th stored vertex id, kept as the "
        "vertex property vrtxid (docs/merge.md)",
    )
    ver_conflicts.add_argument(
        "--format",
        metavar="EXT",
        help="with --export: the file extension (ts, pl, vs, so, vtu, vtp, ply; default: the GOCAD file of the "
        "object's kind, ts for surfaces)",
    )
    ver_conflicts.add_argument("--force", action="store_true", help="with --export: replace existing files")
    ver_resolve = add_command(
        ver_commands,
        "resolve",
        "record how a conflicting object is merged",
        [
            "tgsis version resolve cfm6 feature 42 child",
            "tgsis version resolve cfm6 feature 42 child --discard-other",
            "tgsis version resolve cfm6 42 average --region 0 --discard-other",
            "tgsis version resolve cfm6 42 parent --region all --discard-other",
            "tgsis version resolve cfm6 42 manual --region 0 --mesh edited_child.ts --discard-other",
        ],
        cmd_version_resolve,
    )
    ver_resolve.add_argument("name", help="the child version")
    ver_resolve.add_argument(
        "objectclass", metavar="CLASS", help="object class ('feature' for features); with --region: the feature id"
    )
    ver_resolve.add_argument(
        "objectkey", metavar="KEY", help="object key (for features: the id); with --region: the solution"
    )
    ver_resolve.add_argument(
        "solution",
        nargs="?",
        type=str.lower,
        help="which side the merge keeps: parent, child, manual (the rows as the child has them "
        "after your edit), base (the object as the version was based on it, written into the version and "
        "recorded manual), average (a feature's mesh: the average shape of the two sides, written into the "
        "version and recorded manual), or unsolved (undecided again); a region (--region) takes parent, child, "
        "base, average (each vertex halfway between the two sides), manual (--mesh) or unsolved",
    )
    ver_resolve.add_argument(
        "--region",
        type=_region_argument,
        metavar="N|all",
        help="solve one conflicting region of a feature's mesh (tgsis version conflicts NAME --json lists them "
        "as conflict_regions): tgsis version resolve NAME FEATURE SOLUTION --region N; all: every conflicting "
        "region of the feature at once (parent, child, base, average or unsolved; all or nothing); the merge "
        "takes the regions that are no conflict by itself (docs/merge.md)",
    )
    ver_resolve.add_argument(
        "--mesh",
        metavar="FILE",
        help="with --region and manual: the region's new rows, a mesh file whose vertex property vrtxid holds the "
        "stored vertex ids (as --export writes it: edit the exported child file in GOCAD or ParaView and give it "
        "back); vertices without an id are new",
    )
    ver_resolve.add_argument(
        "--discard-other",
        action="store_true",
        help="record child, parent, base or average even though it throws away edits of the "
        "object since the version was based (without it such a solution is refused, "
        "with the counts; tgsis version conflicts shows them)",
    )

    ver_merge = add_command(
        ver_commands,
        "merge",
        "apply a version's changes to its parent (one transaction)",
        ["tgsis version merge cfm6 --remove"],
        cmd_version_merge,
    )
    ver_merge.add_argument("name", help="the version to merge into its parent")
    ver_merge.add_argument("--remove", action="store_true", help="delete the version after merging it")
    ver_refresh = add_command(
        ver_commands,
        "refresh",
        "bring the parent's changes into a version",
        ["tgsis version refresh cfm6"],
        cmd_version_refresh,
    )
    ver_refresh.add_argument("name", help="the version to refresh")

    ver_diff = add_command(
        ver_commands,
        "diff",
        "objects whose rows differ between two versions or revisions",
        [
            "tgsis version diff DEFAULT cfm6",
            "tgsis version diff cfm6@2 cfm6 --json",
            "tgsis version diff DEFAULT cfm6 --tables",
            "tgsis version diff DEFAULT cfm6 --png out",
        ],
        cmd_version_diff,
        tabular=True,
    )
    ver_diff.add_argument("a", metavar="A[@REVISION]", help="the version (or revision) compared from")
    ver_diff.add_argument("b", metavar="B[@REVISION]", help="the version (or revision) compared to")
    ver_diff.add_argument(
        "--tables",
        action="store_true",
        help="one line per object and table, with its rows added, removed and changed (default: "
        "one line per object saying whether it is only in A, only in B, or changed)",
    )
    ver_diff.add_argument(
        "--png",
        metavar="DIR",
        help="also draw each changed surface feature to DIR/diff_ID.png, coloured by how far its vertices moved from A",
    )

    ver_valid = add_command(
        ver_commands,
        "valid",
        "set the period in which a version was believed true",
        ["tgsis version valid cfm5 2020-01-01 2023-06-30", "tgsis version valid cfm6 2023-06-30"],
        cmd_version_valid,
    )
    ver_valid.add_argument("name", help="the version")
    ver_valid.add_argument("valid_from", metavar="FROM", help="ISO date or time")
    ver_valid.add_argument("valid_to", metavar="TO", nargs="?", help="ISO date or time (omitted: still believed)")
    ver_chain = add_command(
        ver_commands,
        "chain",
        "the chain of believed versions, or the one believed --at a time",
        ["tgsis version chain", "tgsis version chain --at 2024-01-01 --json"],
        cmd_version_chain,
        tabular=True,
    )
    ver_chain.add_argument("--root", default="DEFAULT", help="the version the chain starts from (default: DEFAULT)")
    ver_chain.add_argument("--at", help="ISO date or time: print the version believed then (exit 3: none)")

    ver_compress = add_command(
        ver_commands,
        "compress",
        "remove revisions and row versions no version, named revision or child can reach",
        ["tgsis version compress --dry-run", "tgsis version compress --json"],
        cmd_version_compress,
        tabular=True,
    )
    ver_compress.add_argument("--dry-run", action="store_true", help="only report what would be removed")

    ver_lock = add_command(
        ver_commands,
        "lock",
        "lock objects for a version: no other version may change them",
        ["tgsis version lock cfm6 feature 3 4 --exclusive"],
        cmd_version_lock,
    )
    ver_lock.add_argument("name", help="the version that holds the locks")
    ver_lock.add_argument("objectclass", metavar="CLASS", help="object class ('feature' for features)")
    ver_lock.add_argument("keys", nargs="+", metavar="KEY", help="object keys (feature ids)")
    ver_lock.add_argument(
        "--exclusive", action="store_true", help="also keep other roles from changing them in the version"
    )
    ver_unlock = add_command(
        ver_commands,
        "unlock",
        "release a version's object locks (all, of a class, or some keys)",
        ["tgsis version unlock cfm6", "tgsis version unlock cfm6 feature 3"],
        cmd_version_unlock,
    )
    ver_unlock.add_argument("name", help="the version that holds the locks")
    ver_unlock.add_argument("objectclass", metavar="CLASS", nargs="?", help="only the locks of this object class")
    ver_unlock.add_argument("keys", nargs="*", metavar="KEY", help="only the locks of these keys")
    ver_locks = add_command(
        ver_commands,
        "locks",
        "list object locks (of one version, or all)",
        ["tgsis version locks", "tgsis version locks cfm6 --json"],
        cmd_version_locks,
        tabular=True,
    )
    ver_locks.add_argument("name", nargs="?", help="only the locks of this version")

    privileges = ("write", "create", "merge", "delete", "all")
    for verb in ("grant", "revoke"):
        ver_grant = add_command(
            ver_commands,
            verb,
            f"{verb} a right on a version (owner or tgsis_admin only)",
            [f"tgsis version {verb} cfm6 write {'ana' if verb == 'grant' else 'public'}"],
            cmd_version_grant,
        )
        ver_grant.add_argument("name", help="the version")
        ver_grant.add_argument(
            "privilege", metavar="RIGHT", type=str.lower, choices=privileges, help="one of " + ", ".join(privileges)
        )
        ver_grant.add_argument("role", help="a role, or public")
        ver_grant.set_defaults(revoke=verb == "revoke")
    ver_owner = add_command(
        ver_commands, "owner", "hand a version to another role", ["tgsis version owner cfm6 ana"], cmd_version_owner
    )
    ver_owner.add_argument("name", help="the version")
    ver_owner.add_argument("role", help="its new owner")
    ver_privileges = add_command(
        ver_commands,
        "privileges",
        "owners and granted rights (of one version, or all)",
        ["tgsis version privileges", "tgsis version privileges cfm6 --json"],
        cmd_version_privileges,
        tabular=True,
    )
    ver_privileges.add_argument("name", nargs="?", help="only this version")


def add_versioning_parser(commands: Any) -> None:
    """``tgsis versioning enable|disable|list``."""
    vt = add_command(
        commands, "versioning", "turn versioning of tables on or off", ["tgsis versioning enable features"]
    )
    vt_commands = vt.add_subparsers(dest="versioning_command", metavar="ACTION", required=True)
    vt_enable = add_command(
        vt_commands,
        "enable",
        "version a table (or 'features': model 1 and all feature classes)",
        ["tgsis versioning enable features", "tgsis versioning enable wells --key id --class well"],
        cmd_versioning_enable,
    )
    vt_enable.add_argument("table", help="name or schema.name, or 'features'")
    vt_enable.add_argument("--key", help="column holding the object key")
    vt_enable.add_argument("--class", dest="object_class", help="object class")
    vt_enable.add_argument("--order", type=INT4, default=0, help="iudorder within the object class (default 0)")
    vt_enable.add_argument("--shortname", help="name in conflict reports (default: the table name)")
    vt_disable = add_command(
        vt_commands,
        "disable",
        "make a versioned table plain again with DEFAULT's rows",
        ["tgsis versioning disable wells", "tgsis versioning disable features --force"],
        cmd_versioning_disable,
    )
    vt_disable.add_argument("table", help="name or schema.name, or 'features'")
    vt_disable.add_argument("--force", action="store_true", help="even if versions other than DEFAULT changed it")
    add_command(
        vt_commands,
        "list",
        "list the versioned tables",
        ["tgsis versioning list", "tgsis versioning list --json"],
        cmd_versioning_list,
        tabular=True,
    )
