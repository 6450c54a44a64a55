"""``tgsis class``: feature classes (create, list, alter, drop)."""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import psycopg

from tgsis.cli._arguments import GEOTYPES, INT4, add_command
from tgsis.cli._connection import connection
from tgsis.cli._output import out, print_table, render
from tgsis.cli._render import time_model_suffix
from tgsis.datamodels import data_models
from tgsis.db import versions as V
from tgsis.db.classes import PropertyKind, add_property, drop_property, fill_property_rows, rename_property
from tgsis.db.features import (
    FeatureClass,
    Property,
    create_feature_class,
    drop_feature_class,
    get_feature_class,
    list_feature_classes,
)
from tgsis.db.inspect import other_versions_exist, stored_rows
from tgsis.errors import (
    InvalidInputError,
)
from tgsis.mesh import Geotype

# the time models whose features are G-maps (the registry: models 4 and 5 today)
_GMAP_MODELS = [m.time_model for m in data_models() if "GMAP" in m.geotypes]

# --------------------------------------------------------------------------- feature classes


def _pairs(items: Sequence[str] | None, what: str) -> list[tuple[str, str]]:
    pairs = []
    for item in items or []:
        name, sep, value = item.partition(":")
        if not sep or not name or not value:
            raise InvalidInputError(f"{what} {item!r} must be NAME:TYPE, e.g. porosity:float8")
        pairs.append((name, value))
    return pairs


def _cell_properties(items: Sequence[str] | None, flag: str = "--property") -> list[Property]:
    """``--property NAME:TYPE[:SIZE][:VERTEX|CELL]`` items: a vector of SIZE components, an alignment of its own."""
    result = []
    for item in items or []:
        name, _, rest = item.partition(":")
        words = rest.split(":") if rest else []
        if not name or not words or not words[0] or len(words) > 3:
            raise InvalidInputError(
                f"{flag} {item!r} must be NAME:TYPE[:SIZE][:VERTEX|CELL], e.g. porosity:float8, "
                "slip:float8:3 or facies:int:CELL"
            )
        size, alignment = 1, None
        for word in words[1:]:
            if word.upper() in ("VERTEX", "CELL") and alignment is None:
                alignment = word.upper()
            elif word.isdigit() and size == 1:
                size = int(word)
            else:
                raise InvalidInputError(
                    f"{flag} {item!r}: {word!r} is neither a number of components nor VERTEX or CELL",
                    hint=f"e.g. {flag} slip:float8:3:CELL",
                )
        result.append(Property(name, words[0], size, alignment))  # type: ignore[arg-type]
    return result


def cmd_class_create(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        fc = create_feature_class(
            conn,
            args.name,
            args.geotype,
            feature_properties=_pairs(args.feature_property, "--feature-property"),
            cell_properties=_cell_properties(args.property),
            alignment=args.alignment.upper(),
            srs=args.srs,
            schema=args.schema,
            description=args.description,
            time_model=args.time_model,
            time_unit=args.time_unit,
            instant_properties=_pairs(args.instant_property, "--instant-property"),
            cell_level=args.cell_level,
            versioned=False if args.no_versioning else None,
        )
    pros = f", {fc.protable}" if fc.protable else ""
    other = f", {fc.otherprotable}" if fc.otherprotable else ""
    out(
        f"created feature class {fc.name} ({fc.geotype.value}{time_model_suffix(fc)}) in schema {fc.schema}: "
        f"tables {fc.featuretable}, {fc.cellprotable}{other}{pros}, view {fc.viewname}"
        + ("" if fc.versioned else "; without versioning: one state in every version, written in DEFAULT")
    )
    return 0


def cmd_class_list(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        classes = list_feature_classes(conn)
    return render(args, classes, class_list_text, class_list_json)


def class_list_text(args: argparse.Namespace, classes: list[FeatureClass]) -> None:
    rows = []
    for fc in classes:
        fprops = ", ".join(f"{p.name} {p.type}" for p in fc.feature_properties) or "-"
        cprops = (
            ", ".join(
                f"{p.name} {p.type}{f'[{p.size}]' if p.size > 1 else ''}"
                f"{f' ({p.alignment.lower()})' if p.alignment else ''}"
                for p in fc.cell_properties
            )
            or "-"
        )
        iprops = ", ".join(f"{p.name} {p.type}" for p in fc.instant_properties) or "-"
        rows.append(
            (
                fc.name,
                fc.geotype.value,
                fc.srs,
                fc.schema,
                fc.time_model.lower() + (f" in {fc.time_unit}" if fc.time_unit else ""),
                fprops,
                f"{fc.alignment.lower()}: {cprops}",
                iprops if fc.time_model != "STATIC" else "-",
            )
        )
    print_table(
        args,
        ("class", "geotype", "srs", "schema", "time", "feature properties", "properties", "per-instant properties"),
        rows,
    )
    if not classes:
        print("no feature classes", file=sys.stderr)


def class_list_json(classes: list[FeatureClass]) -> dict[str, Any]:
    return {
        "classes": [
            {
                "name": fc.name,
                "geotype": fc.geotype.value,
                "srs": fc.srs,
                "schema": fc.schema,
                "alignment": fc.alignment,
                "time_model": fc.time_model,
                "time_unit": fc.time_unit,
                "description": fc.description,
                "versioned": fc.versioned,
                "feature_properties": [{"name": p.name, "type": p.type} for p in fc.feature_properties],
                "properties": [
                    {"name": p.name, "type": p.type, "size": p.size, "alignment": p.alignment or fc.alignment}
                    for p in fc.cell_properties
                ],
                "instant_properties": [{"name": p.name, "type": p.type} for p in fc.instant_properties],
            }
            for fc in classes
        ]
    }


def cmd_class_drop(args: argparse.Namespace) -> int:
    with connection(args) as conn:
        deleted = drop_feature_class(conn, args.name, force=args.force)
    out(f"dropped feature class {args.name}" + (f" and its {deleted} feature(s)" if deleted else ""))
    return 0


def _with_default(item: str) -> tuple[str, str | None]:
    """``NAME:TYPE...=VALUE``: the property part and the default value (None without ``=``)."""
    spec, sep, value = item.partition("=")
    return spec, (value if sep else None)


def _property_ref(text: str) -> tuple[str, PropertyKind | None]:
    """``NAME`` or ``KIND:NAME`` (feature, cell, instant: which property when a class has two of that name)."""
    kind, sep, name = text.partition(":")
    if not sep:
        return text, None
    if kind not in ("feature", "cell", "instant") or not name:
        raise InvalidInputError(f"property {text!r} must be NAME or KIND:NAME with KIND feature, cell or instant")
    return name, kind  # type: ignore[return-value]


def _properties_json(fc: FeatureClass) -> dict[str, Any]:
    return {
        "feature_properties": [{"name": p.name, "type": p.type} for p in fc.feature_properties],
        "properties": [
            {"name": p.name, "type": p.type, "size": p.size, "alignment": p.alignment or fc.alignment}
            for p in fc.cell_properties
        ],
        "instant_properties": [{"name": p.name, "type": p.type} for p in fc.instant_properties],
    }


def _stored_count(
    conn: psycopg.Connection[Any],
    fc: FeatureClass,
    kind: str,
    prop: Property | tuple[str, str],
) -> tuple[int, int, str]:
    """How many rows the working version reads with a new property: (rows, geometries, what a row is)."""
    if kind == "feature":
        table, what = fc.featuretable, "feature"
    elif kind == "instant":
        table, what = fc.protable or fc.featuretable, "instant row"
    else:
        alignment = prop.alignment if isinstance(prop, Property) and prop.alignment else fc.alignment
        table, what = fc.property_table(alignment) or fc.cellprotable, f"{alignment.lower()} row"
    rows, geometries = stored_rows(conn, fc, table)
    return rows, geometries, what


def _value_pairs(items: Sequence[str] | None, flag: str) -> dict[str, str]:
    """``NAME=VALUE`` items (repeatable flag)."""
    values: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"{flag} {item[:200]!r} must be NAME=VALUE", hint=f"e.g. {flag} porosity=0.2")
        values[name] = value
    return values


def _shown_value(value: str, typename: str) -> str:
    """A default as output shows it: a number as it is, any other value quoted as an SQL literal."""
    numeric = re.match(r"(small|big)?int|integer|float|double|real|numeric|decimal", typename.strip().lower())
    return value if numeric else "'" + value.replace("'", "''") + "'"


@dataclass(frozen=True)
class ClassAlteration:
    """A class after ``tgsis class alter``, its changes (one dict each, as ``--json`` shows them) and, when other
    versions exist, how the stored rows were counted (``in_versions``: words for people, else empty)."""

    fc: FeatureClass
    changes: list[dict[str, Any]]
    in_versions: str


def cmd_class_alter(args: argparse.Namespace) -> int:
    fills = _value_pairs(args.fill_property, "--fill-property")
    drops = [_property_ref(name) for name in args.drop_property or []]
    renames = [(*_property_ref(old), new) for old, new in args.rename_property or []]
    adds: list[tuple[PropertyKind, Property | tuple[str, str], str | None]] = []
    for item in args.add_feature_property or []:
        spec, default = _with_default(item)
        adds.extend(("feature", pair, default) for pair in _pairs([spec], "--add-feature-property"))
    for item in args.add_property or []:
        spec, default = _with_default(item)
        adds.extend(("cell", prop, default) for prop in _cell_properties([spec], "--add-property"))
    for item in args.add_instant_property or []:
        spec, default = _with_default(item)
        adds.extend(("instant", pair, default) for pair in _pairs([spec], "--add-instant-property"))
    if not (fills or drops or renames or adds):
        raise InvalidInputError(
            "tgsis class alter needs a change",
            hint="give --add-property, --add-feature-property, --add-instant-property, "
            "--rename-property, --drop-property or --fill-property",
        )
    changes: list[dict[str, Any]] = []
    with connection(args) as conn, conn.transaction():  # every change or none
        fc = get_feature_class(conn, args.name)
        if fills:
            for table, (geometries, rows) in fill_property_rows(conn, args.name, fills).items():
                changes.append({"op": "fill", "table": table, "geometries": geometries, "rows": rows, "values": fills})
        for name, kind in drops:
            fc = drop_property(conn, args.name, name, kind=kind, force=args.force)
            changes.append({"op": "drop", "property": name, "kind": kind})
        for old, kind, new in renames:
            fc = rename_property(conn, args.name, old, new, kind=kind)
            changes.append({"op": "rename", "property": old, "kind": kind, "to": new})
        for kind, prop, default in adds:
            fc = add_property(conn, args.name, prop, kind=kind, default=default)
            name, typename = (prop.name, prop.type) if isinstance(prop, Property) else prop
            rows, geometries, what = _stored_count(conn, fc, kind, prop)
            changes.append(
                {
                    "op": "add",
                    "property": name,
                    "kind": kind,
                    "default": default,
                    "type": typename,
                    "stored_rows": rows if default is not None else 0,
                    "stored_geometries": geometries if default is not None else 0,
                    "row": what,
                }
            )
        # the rows were counted as the session's version reads them; add_property gave every version's rows the default
        version = V.working_version(conn)
        in_versions = (
            f" as version {V.show_name(version)} reads them; every version's rows got it"
            if other_versions_exist(conn)
            else ""
        )
    return render(args, ClassAlteration(fc, changes, in_versions), alteration_text, alteration_json)


def alteration_text(args: argparse.Namespace, result: ClassAlteration) -> None:
    fc, changes, in_versions = result.fc, result.changes, result.in_versions
    members = fc.geotype is Geotype.GEOMETRYCOLLECTION
    for change in changes:
        what = f"{change['kind']} property " if change.get("kind") else "property "
        if change["op"] == "fill":
            out(
                f"filled {change['table']}: {change['rows']} row(s) of {change['geometries']} "
                f"{'member(s)' if members else 'feature(s)'} that had none, in every version"
            )
        elif change["op"] == "drop":
            out(f"dropped {what}{change['property']}")
        elif change["op"] == "rename":
            out(f"renamed {what}{change['property']} to {change['to']}")
        elif change["default"] is None:
            out(f"added {what}{change['property']}")
        else:
            default = _shown_value(change["default"], change["type"])
            if change["stored_rows"] == 0 and not in_versions:
                got = f"no stored rows, none got the default {default} (it is not kept: new rows give their own values)"
            elif change["kind"] == "feature":
                got = f"{change['stored_rows']} feature(s) got the default {default}{in_versions}"
            else:
                got = (
                    f"{change['stored_rows']} {change['row']}(s) of {change['stored_geometries']} "
                    f"{'member(s)' if members else 'feature(s)'} got the default {default}{in_versions}"
                )
            out(f"added {what}{change['property']}: {got}")
    cprops = (
        ", ".join(
            f"{p.name} {p.type}{f'[{p.size}]' if p.size > 1 else ''}"
            f"{f' ({p.alignment.lower()})' if p.alignment else ''}"
            for p in fc.cell_properties
        )
        or "-"
    )
    out(
        f"feature class {fc.name}: feature properties "
        f"{', '.join(f'{p.name} {p.type}' for p in fc.feature_properties) or '-'}; "
        f"{fc.alignment.lower()} properties {cprops}"
        + (
            f"; per-instant properties {', '.join(f'{p.name} {p.type}' for p in fc.instant_properties) or '-'}"
            if fc.time_model != "STATIC"
            else ""
        )
    )


def alteration_json(result: ClassAlteration) -> dict[str, Any]:
    return {"class": result.fc.name, "changes": result.changes, **_properties_json(result.fc)}


def add_class_parser(commands: Any) -> None:
    """``tgsis class create|list|alter|drop``."""
    cls = add_command(commands, "class", "feature classes: create, list, alter, drop", ["tgsis class list"])
    cls_commands = cls.add_subparsers(dest="class_command", metavar="ACTION", required=True)
    cls_create = add_command(
        cls_commands,
        "create",
        "register a feature class",
        [
            "tgsis class create faults --geotype SURFACE --srs 32611 --feature-property release:text",
            "tgsis class create moving --geotype SURFACE --time-model EVOLVING --time-unit Ma "
            "--instant-property throw:float8",
            "tgsis class create history --geotype GMAP --time-model MULTIDIM --cell-level 3 --property change_m:float8",
        ],
        cmd_class_create,
    )
    cls_create.add_argument("name", help="the class's name (letters, digits, underscores)")
    cls_create.add_argument(
        "--geotype",
        required=True,
        type=str.upper,
        choices=GEOTYPES,
        help="what its features are: " + ", ".join(GEOTYPES),
    )
    cls_create.add_argument(
        "--feature-property",
        action="append",
        metavar="NAME:TYPE",
        help="a property of the whole feature (repeatable), e.g. creator:text",
    )
    cls_create.add_argument(
        "--property",
        action="append",
        metavar="NAME:TYPE[:SIZE][:VERTEX|CELL]",
        help="a per-vertex (or per-cell) property (repeatable), e.g. porosity:float8; SIZE: a "
        "vector of SIZE components (slip:float8:3); VERTEX or CELL: an alignment other "
        "than --alignment (facies:int:CELL)",
    )
    cls_create.add_argument(
        "--alignment",
        default="VERTEX",
        type=str.upper,
        choices=("VERTEX", "CELL"),
        help="where --property values are unless they say otherwise (default: VERTEX)",
    )
    cls_create.add_argument("--srs", type=INT4, default=0, help="spatial reference id (EPSG), 0 = undefined")
    cls_create.add_argument("--schema", default="public", help="schema of the class's tables (default: public)")
    cls_create.add_argument("--description", help="what the class holds, for people")
    cls_create.add_argument(
        "--time-model",
        default="STATIC",
        type=str.upper,
        choices=[m.time_model for m in data_models()],
        help=", ".join(f"{m.time_model}: {m.name} (model {m.number})" for m in data_models()),
    )
    cls_create.add_argument(
        "--cell-level",
        type=int,
        metavar="LEVEL",
        help=f"classes of G-maps ({', '.join(_GMAP_MODELS)}): the dimension of the cells --property values "
        "belong to (0 vertices, 1 edges, 2 faces, 3 volumes)",
    )
    cls_create.add_argument("--time-unit", help="unit of model time of a temporal class, e.g. Ma")
    cls_create.add_argument(
        "--instant-property",
        action="append",
        metavar="NAME:TYPE",
        help="per-instant feature property of a temporal class (repeatable)",
    )
    cls_create.add_argument(
        "--no-versioning",
        action="store_true",
        help="a class without versioning: its features hold one state that every version sees, "
        'written in DEFAULT only (docs/versioning.md, "Versioning per class")',
    )
    add_command(
        cls_commands,
        "list",
        "list the feature classes",
        ["tgsis class list", "tgsis class list --json"],
        cmd_class_list,
        tabular=True,
    )
    cls_alter = add_command(
        cls_commands,
        "alter",
        "add, rename or drop properties of a feature class, in every version",
        [
            "tgsis class alter horizons --add-property permeability:float8=0 --add-feature-property author:text",
            "tgsis class alter horizons --rename-property porosity phi --drop-property author",
            "tgsis class alter horizons --drop-property phi --force   # deletes its values",
            "tgsis class alter horizons --fill-property porosity=0.2   # features without rows get them",
        ],
        cmd_class_alter,
        tabular=False,
    )
    cls_alter.add_argument("name", help="the class to change")
    cls_alter.add_argument(
        "--add-property",
        action="append",
        metavar="NAME:TYPE[:SIZE][:VERTEX|CELL][=VALUE]",
        help="a new per-vertex (or per-cell) property (repeatable), as for tgsis class create "
        "--property; VALUE: what the stored vertices (cells) get, needed when the class "
        "has features",
    )
    cls_alter.add_argument(
        "--add-feature-property",
        action="append",
        metavar="NAME:TYPE[=VALUE]",
        help="a new property of the whole feature (repeatable); stored features get VALUE, else none (NULL)",
    )
    cls_alter.add_argument(
        "--add-instant-property",
        action="append",
        metavar="NAME:TYPE[=VALUE]",
        help="a new per-instant property of a temporal class (repeatable); stored instants get VALUE, else none (NULL)",
    )
    cls_alter.add_argument(
        "--rename-property",
        action="append",
        nargs=2,
        metavar=("OLD", "NEW"),
        help="rename a property, keeping its values (repeatable); write KIND:OLD (feature, cell, "
        "instant) when the class has two properties called OLD",
    )
    cls_alter.add_argument(
        "--drop-property",
        action="append",
        metavar="NAME",
        help="drop a property (repeatable; KIND:NAME as for --rename-property); refused while "
        "stored values would be lost, unless --force",
    )
    cls_alter.add_argument(
        "--force", action="store_true", help="drop properties even if that deletes their stored values"
    )
    cls_alter.add_argument(
        "--fill-property",
        action="append",
        metavar="NAME=VALUE",
        help="repair: give the stored features that have no rows for the vertex or cell "
        "properties (a property added by tgsis 0.2.0 or earlier to a class without one) a row "
        "per vertex or cell holding VALUE, in every version (repeatable: one per property "
        "of that table); runs before the other changes",
    )
    cls_drop = add_command(
        cls_commands,
        "drop",
        "drop a feature class (refused while it has features)",
        ["tgsis class drop faults", "tgsis class drop faults --force   # with its features"],
        cmd_class_drop,
    )
    cls_drop.add_argument("name", help="the class to drop")
    cls_drop.add_argument("--force", action="store_true", help="also delete its features and their geometries")
