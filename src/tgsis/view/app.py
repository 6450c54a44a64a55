"""The browser view's web application (``tgsis view``): pages and binary mesh endpoints.

A Starlette application served by uvicorn on 127.0.0.1. Every request opens
its own connection with the user's conninfo (so it sees exactly what the
user's role may read) in one transaction, read-only unless the server was
started writable (``default_transaction_read_only``), in the version or
revision the browser chose (a cookie, or ``v=`` on an endpoint), set for that
transaction only (``goto_version(..., local => true)``). It composes no SQL:
storage is read through :mod:`tgsis.db` functions, and how a feature is
drawn comes from its data model's entry in :mod:`tgsis.datamodels`.

Pages: ``/classes`` (feature classes and their features, filtered by class,
name and box), ``/versions`` (the tree, revisions, validity; choosing the
version), ``/scene?ids=...`` (the 3D view, a time slider for temporal
features), ``/compare?id=&a=&b=`` (two versions or revisions of a feature),
``/conflicts?version=`` (a version's conflicts on the mesh). Endpoints:
``/api/mesh/{id}`` and ``/api/compare/{id}`` (bodies of
:func:`tgsis.view.meshes.pack`), ``/api/mesh/{id}/header`` (its header only).
"""

from __future__ import annotations

import contextlib
import math
import urllib.parse
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import Headers, MutableHeaders
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import JSONResponse, PlainTextResponse, RedirectResponse, Response
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles
from starlette.templating import Jinja2Templates
from starlette.types import ASGIApp, Message, Receive, Scope, Send
from starlette.websockets import WebSocketClose

from tgsis import datamodels
from tgsis._merge_slices import SlicedMerge, fixed_period_refusal, merge_sliced
from tgsis.db import versions as V
from tgsis.db._merge_states import SLICE_KEYS, read_sliced_states
from tgsis.db._session import export_snapshot, read_only_by_default, see_one_state
from tgsis.db.classes import FeatureClass, list_feature_classes
from tgsis.db.compare import compare_versions
from tgsis.db.inspect import (
    FeatureRow,
    class_has_feature,
    conflicts_with_solutions,
    count_features,
    feature_name,
    features_versioned,
    list_features,
    may_read_features,
    version_validity,
)
from tgsis.db.merging import object_merge
from tgsis.db.regions import recorded_solutions, sliced_recorded_solutions
from tgsis.drawing import Drawable, StoredSurface, vertex_flags
from tgsis.errors import (
    Error,
    InvalidInputError,
    MissingPrivilegeError,
    NotFoundError,
    ReadOnlyRevisionError,
    VersioningError,
    reraise,
)
from tgsis.merge3 import MeshMerge
from tgsis.mesh import Geotype
from tgsis.view.meshes import pack
from tgsis.view.regions import (
    REGION_COLOURS,
    REGION_LABELS,
    REGION_STATES,
    edit_counts,
    edit_flags,
    region_drawing,
    slice_at,
    slice_json,
    sliced_edit_counts,
    sliced_region_drawing,
    state_drawable,
)

__all__ = ["ViewConfig", "create_app", "VERSION_COOKIE", "RequestGuard"]

Conn = psycopg.Connection[Any]

HERE = Path(__file__).parent
#: the cookie that holds the browser's chosen version (``NAME`` or ``NAME@REVISION``)
VERSION_COOKIE = "tgsis_version"
_BIGINT = 2**63 - 1
#: features listed per class on the classes page (more: filter by name or box)
LISTED = 500


@dataclass(frozen=True)
class ViewConfig:
    """How the view connects.

    Attributes
    ----------
    conninfo : str
        libpq conninfo of the user's database (their own role).
    writable : bool
        False: every transaction is read-only (``default_transaction_read_only``).
    database : str
        Shown in the pages' title bar.
    default_version : str or None
        ``VERSION`` or ``VERSION@REVISION`` of a browser that chose none (None: DEFAULT).
    """

    conninfo: str
    writable: bool = False
    database: str = ""
    default_version: str | None = None


# --------------------------------------------------------------------------- input


def _bad(message: str) -> InvalidInputError:
    return InvalidInputError(message)


def _feature_id(text: str, what: str = "feature id") -> int:
    if not (text.isascii() and text.lstrip("-").isdigit()) or not -_BIGINT - 1 <= int(text) <= _BIGINT:
        raise _bad(f"{what} {text!r} is not a feature id (an integer)")
    return int(text)


def _ids(request: Request) -> list[int]:
    raw = [part for value in request.query_params.getlist("ids") for part in value.split(",") if part.strip()]
    if not raw:
        raise _bad("no feature chosen: give ids=ID (repeatable, or ids=1,2,3)")
    ids = list(dict.fromkeys(_feature_id(p.strip()) for p in raw))
    if len(ids) > 50:
        raise _bad(f"{len(ids)} features: a scene holds at most 50")
    return ids


def _number(text: str | None, what: str) -> float | None:
    if text is None or text == "":
        return None
    try:
        value = float(text)
    except ValueError:
        raise _bad(f"{what} {text!r} is not a number") from None
    if not math.isfinite(value):
        raise _bad(f"{what} {text!r} is not a finite number")
    return value


def _box(text: str | None) -> list[float] | None:
    """``bbox=xmin,ymin,zmin,xmax,ymax,zmax``."""
    if not text:
        return None
    parts = text.split(",")
    if len(parts) != 6:
        raise _bad(f"bbox {text!r} must be xmin,ymin,zmin,xmax,ymax,zmax")
    values = [_number(p.strip(), "bbox value") for p in parts]
    box = [v for v in values if v is not None]
    if len(box) != 6 or any(box[i] > box[i + 3] for i in range(3)):
        raise _bad(f"bbox {text!r} must be xmin,ymin,zmin,xmax,ymax,zmax with each min <= max")
    return box


def split_version(text: str) -> tuple[str, int | None]:
    """``NAME`` or ``NAME@REVISION`` (an InvalidInputError naming the text otherwise)."""
    name, sep, revision = text.partition("@")
    if not name:
        raise _bad(f"version {text!r} has no name")
    if not sep:
        return name, None
    if not (revision.isascii() and revision.isdigit()) or int(revision) > 2**31 - 1:
        raise _bad(f"version {text!r} is not VERSION or VERSION@REVISION")
    return name, int(revision)


# --------------------------------------------------------------------------- database


class View:
    """The application's state: its configuration and templates; one connection per request."""

    def __init__(self, config: ViewConfig) -> None:
        self.config = config
        self.templates = Jinja2Templates(directory=str(HERE / "templates"))
        self.templates.env.globals["quote"] = lambda text: urllib.parse.quote(str(text), safe="")
        # a coordinate for people: metres to the decimetre at UTM scale, small values to 6 digits
        self.templates.env.globals["coord"] = lambda v: f"{v:.1f}" if abs(v) >= 1000 else f"{v:.6g}"

    @contextlib.contextmanager
    def session(self, request: Request, version: str | None = None, *, snapshot: str | None = None) -> Iterator[Conn]:
        """A connection inside one transaction, in ``version`` (else the browser's choice, else DEFAULT).

        The transaction is REPEATABLE READ: every query of a page sees one
        state of the database; ``snapshot`` (of ``pg_export_snapshot()``)
        makes it see the state another session sees.
        """
        chosen = version if version is not None else self.chosen(request)
        with reraise(), psycopg.connect(self.config.conninfo) as conn:
            if not self.config.writable:
                read_only_by_default(conn)
            with conn.transaction():
                see_one_state(conn, snapshot)
                if chosen:
                    name, revision = split_version(chosen)
                    if revision is None:
                        V.goto_version(conn, name, local=True)
                    else:
                        V.goto_revision(conn, name, revision, local=True)
                yield conn

    @contextlib.contextmanager
    def beside(self, conn: Conn, request: Request, version: str | None = None) -> Iterator[Conn]:
        """A second connection that sees what ``conn`` sees (its snapshot, the same version): for queries side by side."""
        with self.session(request, version, snapshot=export_snapshot(conn)) as other:
            yield other

    def chosen(self, request: Request) -> str | None:
        """The browser's version (its cookie), else the server's default."""
        return request.cookies.get(VERSION_COOKIE) or self.config.default_version

    def page(self, request: Request, template: str, status_code: int = 200, **context: Any) -> Response:
        return self.templates.TemplateResponse(
            request,
            template,
            {
                "database": self.config.database,
                "writable": self.config.writable,
                "chosen_version": self.chosen(request) or "DEFAULT",
                "title": None,
                **context,
            },
            status_code=status_code,
        )


def readable_classes(conn: Conn) -> list[tuple[FeatureClass, bool]]:
    """Every feature class with whether the role may read its feature table."""
    result = []
    for fc in list_feature_classes(conn):
        result.append((fc, may_read_features(conn, fc)))
    return result


def feature_class_of(conn: Conn, feature_id: int) -> FeatureClass:
    """The class holding ``feature_id`` among the classes the role may read (NotFoundError otherwise)."""
    for fc, readable in readable_classes(conn):
        if readable and class_has_feature(conn, fc, feature_id):
            return fc
    raise NotFoundError(
        f"no feature {feature_id} that this role can read in this version", hint="the classes page lists the features"
    )


def _scalar_vertex_properties(fc: FeatureClass) -> list[str]:
    numeric = (
        "float4",
        "float8",
        "int2",
        "int4",
        "int8",
        "real",
        "double precision",
        "integer",
        "smallint",
        "bigint",
        "numeric",
    )
    return [p.name for p in fc.aligned("VERTEX") if p.size == 1 and p.type in numeric]


# How a feature is drawn comes from the registry of data models (tgsis.datamodels): the hooks its model's
# module attaches (Storage.draw, life, colours, surface). Nothing here names a model.


def _drawing(fc: FeatureClass, feature_id: int) -> datamodels.Storage:
    """The hooks of the data model of ``fc``; an InvalidInputError naming the model when the view cannot draw it."""
    model = datamodels.data_model(fc.time_model)
    storage = datamodels.storage_of(model)
    if storage.draw is None:
        drawn = [f"{m.number} ({m.time_model})" for m in datamodels.data_models() if _draws(m)]
        raise _bad(
            f"feature {feature_id} (class {fc.name}) belongs to data model {model.number} ({model.time_model}), "
            f"which the browser view does not draw: it draws data models {', '.join(drawn)}"
        )
    return storage


def _draws(model: datamodels.DataModel) -> bool:
    try:
        return datamodels.storage_of(model).draw is not None
    except InvalidInputError:  # its database functions are not attached: not drawn either
        return False


def _colours(conn: Conn, fc: FeatureClass, feature_id: int) -> list[str]:
    """What a feature can be coloured by besides height: its model's choice, else the class's numeric vertex properties."""
    colours = _drawing(fc, feature_id).colours
    return colours(conn, fc, feature_id) if colours is not None else _scalar_vertex_properties(fc)


def _life(conn: Conn, fc: FeatureClass, feature_id: int) -> tuple[float, float] | None:
    """The span the time slider covers for a feature (None: a model without time, or nothing stored yet)."""
    life = _drawing(fc, feature_id).life
    return None if life is None else life(conn, feature_id)


def _time_of(
    lives: Sequence[tuple[float, float] | None], t: float | None
) -> tuple[float | None, float | None, float | None]:
    """(t, first, last) for a scene: t checked against the temporal features' lives (default: the last instant)."""
    known = [life for life in lives if life is not None]
    if not known:
        return None, None, None
    first = min(a for a, _ in known)
    last = max(b for _, b in known)
    if t is None:
        return last, first, last
    if not first <= t <= last:
        raise _bad(f"t = {t!r} is outside the life of the features shown: from {first!r} to {last!r}")
    return t, first, last


def _mesh_of(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    t: float | None,
    color: str | None = None,
    beside: Callable[[], contextlib.AbstractContextManager[Conn]] | None = None,
) -> tuple[Drawable | None, float | None]:
    """What to draw of a feature at t (None when it does not exist then) and the t used (None: a model without time)."""
    drawing = _drawing(fc, feature_id)
    assert drawing.draw is not None
    if drawing.life is None:  # drawn whole, whatever t
        return drawing.draw(conn, fc, feature_id, None, colour=color, beside=beside), None
    # any finite t (a scene's slider spans the lives of all its features): outside this one's life, nothing
    life = drawing.life(conn, feature_id)
    when = t if t is not None else (None if life is None else life[1])
    if when is None:
        return None, None
    return drawing.draw(conn, fc, feature_id, when, colour=color, beside=beside), when


def _origin(vertices: npt.NDArray[np.float64]) -> list[float]:
    if len(vertices) == 0:
        return [0.0, 0.0, 0.0]
    return [float(v) for v in (vertices.min(axis=0) + vertices.max(axis=0)) / 2]


def _body(
    header: Mapping[str, Any],
    mesh: Drawable | None,
    color: str | None,
    extra: Mapping[str, npt.NDArray[Any]] | None = None,
) -> bytes:
    arrays: dict[str, npt.NDArray[Any]] = {}
    if mesh is None:
        return pack(
            {**header, "kind": "none", "origin": [0.0, 0.0, 0.0], "n_vertices": 0, "n_cells": 0, "properties": []}, {}
        )
    origin = _origin(mesh.vertices)
    arrays["positions"] = mesh.vertices - np.asarray(origin)
    arrays["indices"] = mesh.indices
    if color:
        if color not in mesh.vertex_values:
            raise _bad(
                f"feature {header.get('id')} has no numeric vertex property {color!r}: it has "
                f"{', '.join(sorted(mesh.vertex_values)) or 'none'}"
            )
        arrays["values"] = mesh.vertex_values[color]
    arrays.update(extra or {})
    return pack(
        {
            **header,
            "kind": mesh.kind,
            "origin": origin,
            "n_vertices": int(len(mesh.vertices)),
            "n_cells": int(len(mesh.indices)),
            "color": color,
            "properties": sorted(mesh.vertex_values),
        },
        arrays,
    )


def _binary(body: bytes) -> Response:
    return Response(body, media_type="application/octet-stream", headers={"Cache-Control": "no-store"})


# --------------------------------------------------------------------------- pages


def classes_page(request: Request) -> Response:
    view: View = request.app.state.view
    wanted = request.query_params.get("class") or None
    name = request.query_params.get("name") or None
    box = _box(request.query_params.get("bbox"))
    with view.session(request) as conn:
        classes = readable_classes(conn)
        known = {fc.name for fc, _ in classes}
        if wanted is not None and wanted not in known:
            raise NotFoundError(f"no feature class {wanted!r}", hint="the classes page lists them")
        counts: dict[str, int | None] = {}
        features: list[FeatureRow] = []
        truncated: list[str] = []
        for fc, readable in classes:
            if not readable:
                counts[fc.name] = None
                continue
            counts[fc.name] = count_features(conn, fc)
            if wanted is None or wanted == fc.name:
                found = list_features(conn, fc, name=name, box=box, limit=LISTED + 1)
                if len(found) > LISTED:
                    truncated.append(fc.name)
                features += found[:LISTED]
        version = V.working_version(conn)
    return view.page(
        request,
        "classes.html",
        classes=classes,
        counts=counts,
        features=features,
        wanted=wanted,
        truncated=truncated,
        listed=LISTED,
        name=name or "",
        bbox=request.query_params.get("bbox") or "",
        version=version,
    )


def versions_page(request: Request) -> Response:
    view: View = request.app.state.view
    with view.session(request) as conn:
        versions = V.list_versions(conn)
        validity = version_validity(conn)
        current, viewing = V.working_version(conn), V.viewing_revision(conn)
        versioned = features_versioned(conn)
    return view.page(
        request,
        "versions.html",
        versions=versions,
        validity=validity,
        current=current,
        viewing=viewing,
        versioned=versioned,
    )


async def choose_version(request: Request) -> Response:
    """POST ``version=NAME`` or ``NAME@REVISION``: the browser's version from now on (a cookie), once it is checked."""
    view: View = request.app.state.view
    form = urllib.parse.parse_qs((await request.body()).decode("utf-8", "replace"))
    chosen = (form.get("version") or [""])[0] or "DEFAULT"

    def check() -> None:
        with view.session(request, chosen):
            pass

    await run_in_threadpool(check)  # an unknown version or revision: the error page, the cookie unchanged
    response = RedirectResponse("/versions", status_code=303)
    response.set_cookie(VERSION_COOKIE, chosen, samesite="strict", httponly=True)
    return response


def _scene_rows(conn: Conn, ids: Sequence[int]) -> list[tuple[FeatureRow, FeatureClass, tuple[float, float] | None]]:
    """Each feature's row, class and life (the span of the time slider; None: drawn whatever t)."""
    rows = []
    for feature_id in ids:
        fc = feature_class_of(conn, feature_id)
        _drawing(fc, feature_id)
        rows += [(row, fc, _life(conn, fc, feature_id)) for row in list_features(conn, fc, ids=[feature_id])]
    return rows


def scene_page(request: Request) -> Response:
    view: View = request.app.state.view
    ids = _ids(request)
    t = _number(request.query_params.get("t"), "time t")
    color = request.query_params.get("color") or "height"
    exaggeration = _number(request.query_params.get("exaggeration"), "vertical exaggeration") or 1.0
    if not 0.01 <= exaggeration <= 1000:
        raise _bad(f"vertical exaggeration {exaggeration!r} must be from 0.01 to 1000")
    with view.session(request) as conn:
        shown = _scene_rows(conn, ids)
        when, first, last = _time_of([life for _, _, life in shown], t)
        properties = sorted(set.intersection(*(set(_colours(conn, fc, r.id)) for r, fc, _ in shown)))
        version = V.working_version(conn)
    rows = [r for r, _, _ in shown]
    if color != "height" and color not in properties:
        raise _bad(
            f"colour {color!r} is neither 'height' nor a numeric vertex property of every feature shown "
            f"({', '.join(properties) or 'none'})"
        )
    units = {fc.time_unit for _, fc, life in shown if life is not None} - {None}
    temporal = [r.id for r, _, life in shown if life is not None]

    def first_url(feature_id: int) -> str:
        params = {"t": repr(when) if feature_id in temporal else None, "color": None if color == "height" else color}
        return f"/api/mesh/{feature_id}?" + urllib.parse.urlencode({k: v for k, v in params.items() if v is not None})

    config = {
        "ids": ids,
        "t": when,
        "first": first,
        "last": last,
        "color": color,
        "exaggeration": exaggeration,
        "temporal": temporal,
        "urls": {str(i): first_url(i) for i in ids},
    }
    comparable = len(shown) == 1 and _compared(shown[0][1])
    return view.page(
        request,
        "scene.html",
        rows=rows,
        config=config,
        properties=properties,
        color=color,
        comparable=comparable,
        unit=", ".join(sorted(u for u in units if u)),
        version=version,
        title="scene",
    )


def compare_page(request: Request) -> Response:
    view: View = request.app.state.view
    feature_id = _feature_id(request.query_params.get("id") or "")
    a = request.query_params.get("a") or "DEFAULT"
    b = request.query_params.get("b") or view.chosen(request) or "DEFAULT"
    mode = request.query_params.get("mode") or "displacement"
    if mode not in ("side", "displacement"):
        raise _bad(f"mode {mode!r} must be 'side' or 'displacement'")
    for text in (a, b):
        split_version(text)
    with view.session(request) as conn:
        versions = V.list_versions(conn)
    with view.session(request, a) as conn:
        fc = feature_class_of(conn, feature_id)
        _comparison(fc, feature_id)
        row = list_features(conn, fc, ids=[feature_id])[0]
        (a_name, a_rev), (b_name, b_rev) = split_version(a), split_version(b)
        changes = compare_versions(conn, feature_id, a_name, b_name, old_revision=a_rev, new_revision=b_rev)
    config = {"id": feature_id, "a": a, "b": b, "mode": mode, "marks": request.query_params.get("marks") != "0"}
    return view.page(
        request,
        "compare.html",
        row=row,
        config=config,
        changes=changes.counts(),
        a=a,
        b=b,
        mode=mode,
        versions=versions,
        title="compare",
    )


def conflicts_page(request: Request) -> Response:
    view: View = request.app.state.view
    version = request.query_params.get("version") or ""
    name, revision = split_version(version)
    if revision is not None:
        raise _bad(f"conflicts belong to a version, not to a revision: {version!r}")
    with view.session(request) as conn:
        known = {v.name: v for v in V.list_versions(conn)}
        if name not in known:
            raise NotFoundError(f"no version {name!r}", hint="the versions page lists them")
        if known[name].parent is None:
            raise _bad("DEFAULT has no parent: it has no conflicts")
        conflicts = conflicts_with_solutions(conn, name)
    shown = [int(c["objectkey"]) for c in conflicts if c["objectclass"] == "feature"]
    legend = [{"state": s, "label": REGION_LABELS[s], "colour": REGION_COLOURS[s]} for s in REGION_STATES]
    t = _number(request.query_params.get("t"), "time t")  # the slice drawn of a model-2/3 feature's regions
    timem = _number(request.query_params.get("timem"), "period start timem")  # model 3: the period of t
    config = {"version": name, "parent": known[name].parent, "ids": shown, "legend": legend, "t": t, "timem": timem}
    return view.page(
        request, "conflicts.html", version=known[name], conflicts=conflicts, config=config, title="conflicts"
    )


# --------------------------------------------------------------------------- binary endpoints


def _mesh_body(request: Request) -> bytes:
    view: View = request.app.state.view
    feature_id = _feature_id(request.path_params["id"])
    t = _number(request.query_params.get("t"), "time t")
    color = request.query_params.get("color") or None
    color = None if color == "height" else color
    version = request.query_params.get("v")
    mesh: Drawable | None
    with view.session(request, version) as conn:
        fc = feature_class_of(conn, feature_id)
        mesh, when = _mesh_of(conn, fc, feature_id, t, color, lambda: view.beside(conn, request, version))
        name = feature_name(conn, feature_id)
    return _body({"id": feature_id, "class": fc.name, "name": name, "t": when}, mesh, color)


def mesh_endpoint(request: Request) -> Response:
    return _binary(_mesh_body(request))


def mesh_header_endpoint(request: Request) -> Response:
    body = _mesh_body(request)
    n = int(np.frombuffer(body[:4], dtype="<u4")[0])
    return Response(body[4 : 4 + n].rstrip(), media_type="application/json")


def _compared(fc: FeatureClass) -> bool:
    """Whether the view compares versions of the features of ``fc``: surfaces of a model with a ``surface`` hook."""
    try:
        storage = datamodels.storage_of(datamodels.data_model(fc.time_model))
    except InvalidInputError:
        return False
    return storage.surface is not None and fc.geotype is Geotype.SURFACE


def _comparison(fc: FeatureClass, feature_id: int) -> datamodels.SurfaceFunction:
    """The hook that reads a feature of ``fc`` as a stored surface, or an InvalidInputError saying what is compared."""
    surface = datamodels.storage_of(datamodels.data_model(fc.time_model)).surface
    if surface is None or fc.geotype is not Geotype.SURFACE:
        models = [f"{m.number} ({m.time_model})" for m in datamodels.data_models() if _compares(m)]
        raise _bad(
            f"feature {feature_id} (class {fc.name}: {fc.geotype.value}, {fc.time_model}) is not a surface "
            f"the view compares between versions: it compares the surfaces of data models {', '.join(models)}"
        )
    return surface


def _compares(model: datamodels.DataModel) -> bool:
    try:
        return datamodels.storage_of(model).surface is not None
    except InvalidInputError:
        return False


def _surface_in(view: View, request: Request, version: str, feature_id: int) -> StoredSurface:
    with view.session(request, version) as conn:
        fc = feature_class_of(conn, feature_id)
        stored: StoredSurface = _comparison(fc, feature_id)(conn, fc, feature_id)
        return stored


def _positions(ids: npt.NDArray[np.int64], wanted: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """Indices in ``ids`` (ascending) of the ``wanted`` ids that are there."""
    w = np.asarray(wanted, dtype=np.int64)
    at = np.searchsorted(ids, w)
    ok = (at < len(ids)) & (ids[np.minimum(at, len(ids) - 1)] == w) if len(ids) else np.zeros(len(w), dtype=bool)
    found: npt.NDArray[np.int64] = at[ok].astype(np.int64)
    return found


def compare_endpoint(request: Request) -> Response:
    """One side of a comparison: the mesh in version a or b, changed vertices flagged, b's displacement from a."""
    view: View = request.app.state.view
    feature_id = _feature_id(request.path_params["id"])
    a, b = request.query_params.get("a") or "", request.query_params.get("b") or ""
    side = request.query_params.get("side") or "b"
    if side not in ("a", "b"):
        raise _bad(f"side {side!r} must be 'a' or 'b'")
    (a_name, a_rev), (b_name, b_rev) = split_version(a), split_version(b)
    stored_a, stored_b = _surface_in(view, request, a, feature_id), _surface_in(view, request, b, feature_id)
    mesh_a, vids_a, tids_a = stored_a.drawable, stored_a.vertex_ids, stored_a.triangle_ids
    mesh_b, vids_b, tids_b = stored_b.drawable, stored_b.vertex_ids, stored_b.triangle_ids
    with view.session(request) as conn:
        changes = compare_versions(conn, feature_id, a_name, b_name, old_revision=a_rev, new_revision=b_rev)
    if side == "a":
        removed_cells = _positions(tids_a, changes.cells_removed)
        flags = vertex_flags(
            len(mesh_a.vertices),
            [(1, _positions(vids_a, changes.vertices_removed)), (1, mesh_a.indices[removed_cells].ravel())],
        )
        mesh, extra = mesh_a, {"changed": flags}
    else:
        added_cells = _positions(tids_b, changes.cells_added)
        flags = vertex_flags(
            len(mesh_b.vertices),
            [(1, _positions(vids_b, changes.vertices_added)), (1, mesh_b.indices[added_cells].ravel())],
        )
        displacement = np.full(len(mesh_b.vertices), np.nan)
        at = np.searchsorted(vids_a, vids_b)
        at = np.minimum(at, max(len(vids_a) - 1, 0))
        same = (vids_a[at] == vids_b) if len(vids_a) else np.zeros(len(vids_b), dtype=bool)
        displacement[same] = np.linalg.norm(mesh_b.vertices[same] - mesh_a.vertices[at[same]], axis=1)
        mesh, extra = mesh_b, {"changed": flags, "displacement": displacement}
    header = {"id": feature_id, "side": side, "version": a if side == "a" else b, "changes": changes.counts()}
    return _binary(_body(header, mesh, None, extra))


def conflict_endpoint(request: Request) -> Response:
    """A conflicting feature as the version sees it, with its merge regions (:mod:`tgsis.view.regions`).

    An object that merges by region (:func:`tgsis.object_merge`, any model-1
    kind) is drawn from the merge's child state, with the regions (header
    ``regions``; arrays ``region_vertices``, ``region_cells``: positions in the
    drawn arrays), the solution recorded for each, read in the same snapshot,
    and per vertex ``changed``: changed in the version (1), in the parent (2),
    both (3), from the merge's edits. One that merges as a whole only says why
    (``reason``); a surface is then flagged by comparing the meshes by
    content, another kind drawn unflagged.

    A model-2/3 surface merges slice by slice (an instant, a geometry
    instant): ``t`` chooses the slice drawn, model 3's ``timem`` the period
    whose geometry instant it is (a period's last is the next one's start;
    :func:`tgsis.view.regions.slice_at`; none given: the first with a
    conflict), whose regions are drawn on its
    child mesh as model 1's; every region of the object is listed with its
    ``slice`` and ``at_t``. Header ``slice`` (None when no merged slice is at
    ``t``: the object is drawn at ``t`` as the scene draws it, no region on it)
    and ``t``.
    """
    view: View = request.app.state.view
    feature_id = _feature_id(request.path_params["id"])
    version = request.query_params.get("version") or ""
    t = _number(request.query_params.get("t"), "time t")
    timem = _number(request.query_params.get("timem"), "period start timem")
    name, revision = split_version(version)
    if revision is not None:
        raise _bad(f"conflicts belong to a version, not to a revision: {version!r}")
    with view.session(request) as conn:
        known = {v.name: v for v in V.list_versions(conn)}
    if name not in known or known[name].parent is None:
        raise NotFoundError(f"no version {name!r} with a parent", hint="the versions page lists them")
    parent, base = known[name].parent, known[name].initrevision
    assert parent is not None
    regions: list[dict[str, Any]] = []
    region_arrays = {n: np.empty(0, dtype=np.int64) for n in ("region_vertices", "region_cells")}
    counts: dict[str, dict[str, int]] = {"child": {}, "parent": {}}
    recorded = "none"
    drawn_slice: dict[str, float] | None = None
    drawn_t: float | None = None
    merge: MeshMerge | SlicedMerge | str
    with view.session(request, name) as conn:
        fc = feature_class_of(conn, feature_id)
        if fc.time_model in SLICE_KEYS:
            merge = _sliced_merge(conn, name, feature_id)
        else:
            merge = _object_merge(conn, name, feature_id)
        if isinstance(merge, SlicedMerge):
            # the slice at t drawn from the merge's child state of that slice, as a model-1 object's merge
            solutions, recorded = _recorded_sliced_solutions(conn, name, feature_id, merge)
            key = slice_at(merge, t, timem)
            regions, region_arrays = sliced_region_drawing(merge, key, solutions)
            counts = sliced_edit_counts(merge)
            if key is not None:
                at = merge.merges[key]
                mesh, _ = state_drawable(at.child)
                flags = edit_flags(at, at.child.vertex_ids, merged=True)
                drawn_slice, drawn_t = slice_json(key), float(key[-1])
            else:  # no merged slice at t: the object at t as the scene draws it, no region on it
                drawable, drawn_t = _mesh_of(conn, fc, feature_id, t)
                if drawable is None:
                    raise NotFoundError(f"feature {feature_id} does not exist at t = {t:g} in version {name!r}")
                mesh, flags = drawable, np.zeros(len(drawable.vertices), dtype=np.float32)
        elif isinstance(merge, MeshMerge):
            # drawn from the merge's own child state (the version's rows, read in the merge's snapshot): one read,
            # any model-1 kind, the regions' ids in the drawing's numbering
            solutions, recorded = _recorded_solutions(conn, name, feature_id, merge)
            mesh, drawn_cells = state_drawable(merge.child)
            regions, region_arrays = region_drawing(merge, merge.child.vertex_ids, drawn_cells, solutions, merged=True)
            # who changed each vertex: the merge's own id-keyed edits, no second comparison of the meshes
            flags, counts = edit_flags(merge, merge.child.vertex_ids, merged=True), edit_counts(merge)
        elif _compared(fc):
            stored: StoredSurface = _comparison(fc, feature_id)(conn, fc, feature_id)
        else:  # merges as a whole only and not compared: drawn, nobody's changes marked
            drawable, drawn_t = _mesh_of(conn, fc, feature_id, t)
            if drawable is None:
                raise NotFoundError(f"feature {feature_id} has no geometry in version {name!r}")
            mesh, flags = drawable, np.zeros(len(drawable.vertices), dtype=np.float32)
    if isinstance(merge, str) and _compared(fc):
        # merges as a whole only: who changed what, by comparing the meshes by content (the merge knows nothing)
        mesh, vids, tids = stored.drawable, stored.vertex_ids, stored.triangle_ids
        with view.session(request) as conn:
            child = compare_versions(conn, feature_id, parent, name, old_revision=base)
            theirs = compare_versions(conn, feature_id, parent, parent, old_revision=base)
        marks = []
        for flag, changes in ((1, child), (2, theirs)):
            cells = _positions(tids, np.concatenate([changes.cells_added, changes.cells_removed]))
            marks += [
                (flag, _positions(vids, np.concatenate([changes.vertices_added, changes.vertices_removed]))),
                (flag, mesh.indices[cells].ravel()),
            ]
        flags = vertex_flags(len(mesh.vertices), marks)
        counts = {"child": child.counts(), "parent": theirs.counts()}
    header = {
        "id": feature_id,
        "version": name,
        "parent": parent,
        "base": base,
        "child_changes": counts["child"],
        "parent_changes": counts["parent"],
        "merges_by_region": not isinstance(merge, str),
        "reason": merge if isinstance(merge, str) else None,
        "regions": regions,
        "solutions": recorded,
        "slice": drawn_slice,
        "t": drawn_t,
    }
    extra: dict[str, npt.NDArray[Any]] = {"changed": flags, **region_arrays}
    return _binary(_body(header, mesh, None, extra))


def _object_merge(conn: Conn, version: str, feature_id: int) -> MeshMerge | str:
    """:func:`tgsis.object_merge` in the caller's snapshot, or why the object has no regions (it merges whole)."""
    try:
        return object_merge(conn, version, feature_id)
    except (InvalidInputError, VersioningError, MissingPrivilegeError) as exc:
        return str(exc).splitlines()[0]


def _sliced_merge(conn: Conn, version: str, feature_id: int) -> SlicedMerge | str:
    """The slice-by-slice merge of a model-2/3 feature in the caller's snapshot, or why it merges as a whole only."""
    try:
        with reraise(), conn.transaction():  # a savepoint: a refused read leaves the page's transaction usable
            states = read_sliced_states(conn, version, feature_id).states
        merge = merge_sliced(states["base"], states["parent"], states["child"])
    except (InvalidInputError, VersioningError, MissingPrivilegeError) as exc:
        return str(exc).splitlines()[0]
    refusal = fixed_period_refusal(merge)  # TG308 whatever the solutions: it merges as a whole only
    return merge if refusal is None else refusal


def _recorded_sliced_solutions(
    conn: Conn, version: str, feature_id: int, merge: SlicedMerge
) -> tuple[dict[int, str], str]:
    """:func:`_recorded_solutions` of a model-2/3 merge (regions numbered in the object)."""
    solutions = sliced_recorded_solutions(conn, version, "feature", str(feature_id), merge)
    if solutions is None:
        return {}, "stale"
    return solutions, "recorded" if solutions else "none"


def _recorded_solutions(conn: Conn, version: str, feature_id: int, merge: MeshMerge) -> tuple[dict[int, str], str]:
    """The solution recorded for each region of ``merge`` (:func:`tgsis.db.regions.recorded_solutions`), and whether:

    ``recorded`` (they hold for this merge), ``none`` (no region stored: every
    conflict unsolved), ``stale`` (found on another state: shown unsolved until
    the conflicts are found again).
    """
    solutions = recorded_solutions(conn, version, "feature", str(feature_id), merge)
    if solutions is None:
        return {}, "stale"
    return solutions, "recorded" if solutions else "none"


# --------------------------------------------------------------------------- request guard

#: the methods a page of another site may make a browser send without harm: they change nothing
SAFE_METHODS = frozenset({"GET", "HEAD"})
#: on every response: no page of another site shows the view in a frame (its own buttons under a decoy
#: would send the view's own Origin: clickjacking)
UNFRAMED = {"X-Frame-Options": "DENY", "Content-Security-Policy": "frame-ancestors 'none'"}


def _origin_of(url: str) -> tuple[str, str, int] | None:
    """``(scheme, host, port)`` of an absolute http(s) URL or origin (default port filled in), None if it is not one."""
    try:
        parts = urllib.parse.urlsplit(url.strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme.lower() not in ("http", "https") or not parts.hostname:
        return None
    scheme = parts.scheme.lower()
    return scheme, parts.hostname.lower(), port if port is not None else (443 if scheme == "https" else 80)


def _shown(origin: tuple[str, str, int]) -> str:
    scheme, host, port = origin
    host = f"[{host}]" if ":" in host else host
    default = 443 if scheme == "https" else 80
    return f"{scheme}://{host}" + ("" if port == default else f":{port}")


class RequestGuard:
    """Refuses the requests a page of another site can make a browser send to the view.

    Wraps the whole application (every route, present and future), before
    routing:

    - a ``Host`` header that is not one of ``hosts`` gets 400: a page of an
      attacker's site whose name resolves to this machine (DNS rebinding)
      reaches the socket, not the view;
    - a request whose method is not GET or HEAD (the only ones that change
      something: ``POST /session`` chooses the browser's version) must come
      from the view's own pages: its ``Origin`` (or, when a browser sends
      none, its ``Referer``) must be the view's own origin (scheme, the
      ``Host`` it was sent to, port). A foreign, opaque (``null``) or
      malformed origin, or neither header, gets 403 with a message saying
      why; browsers send ``Origin`` on every POST, so only scripts
      (curl) lack it, and they can send it. A websocket (none today) is
      checked the same way, and closed with 1008 when refused;
    - every response forbids framing (``X-Frame-Options: DENY``,
      ``frame-ancestors 'none'``): the view's own buttons in a frame of
      another site's page, under a decoy, would pass the origin check.

    Parameters
    ----------
    app : ASGI application
    hosts : sequence of str
        The host names (or addresses) the view answers to.
    """

    def __init__(self, app: ASGIApp, hosts: Sequence[str]) -> None:
        self.app = app
        self.hosts = frozenset(h.strip("[]").lower() for h in hosts)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refusal = self.refusal(scope)
        if scope["type"] == "websocket":  # none today; a future one is checked like a POST (browsers send its Origin)
            if refusal is not None:
                await WebSocketClose(code=1008, reason=f"refused: {refusal.status_code}")(scope, receive, send)
            else:
                await self.app(scope, receive, send)
            return

        async def send_unframed(message: Message) -> None:
            if message["type"] == "http.response.start":
                MutableHeaders(scope=message).update(UNFRAMED)
            await send(message)

        if refusal is not None:
            await refusal(scope, receive, send_unframed)
            return
        await self.app(scope, receive, send_unframed)

    def refusal(self, scope: Scope) -> Response | None:
        """The response refusing this request, or None to let it through."""
        headers = Headers(scope=scope)
        scheme = "https" if scope.get("scheme") in ("https", "wss") else "http"
        host = headers.get("host", "")
        own = _origin_of(f"{scheme}://{host}") if host and "/" not in host and "@" not in host else None
        if own is None or own[1] not in self.hosts:
            return PlainTextResponse(
                f"400 Bad Request: tgsis view answers requests for {', '.join(sorted(self.hosts))}, "
                f"not for the host {host[:200]!r} (a page of another site reaching this machine under a "
                "name of its own gets nothing; start the view with --host NAME to answer to NAME)",
                status_code=400,
            )
        method = str(scope.get("method", "GET")).upper() if scope["type"] == "http" else "WEBSOCKET"
        if scope["type"] == "http" and method in SAFE_METHODS:
            return None
        origin, referer = headers.get("origin"), headers.get("referer")
        if origin is not None:
            source, said = _origin_of(origin), f"comes from {origin[:200]}"
        elif referer is not None:
            source = _origin_of(referer)
            said = f"comes from a page of {_shown(source) if source else repr(referer[:200])}"
        else:
            source, said = None, "names neither Origin nor Referer"
        if source == own:
            return None
        here = _shown(own)
        return PlainTextResponse(
            f"403 Forbidden: tgsis view refused {method} {scope.get('path', '')}: the request {said}; "
            f"the view accepts changes (the version a browser works in) only from its own pages ({here}). "
            f"Open {here}/versions and choose the version there (a script: send the header 'Origin: {here}').",
            status_code=403,
        )


# --------------------------------------------------------------------------- errors


_STATUS = ((NotFoundError, 404), (MissingPrivilegeError, 403), (ReadOnlyRevisionError, 403))


def _status_of(exc: Error) -> int:
    for cls, status in _STATUS:
        if isinstance(exc, cls):
            return status
    if exc.sqlstate == "25006":  # read_only_sql_transaction: the view was not started --writable
        return 403
    return 400 if not (exc.sqlstate or "").startswith(("08", "53", "57", "58", "XX")) else 500


async def error_page(request: Request, exc: Exception) -> Response:
    """An error page (or, for the endpoints, a JSON error) with the status and the message."""
    view: View = request.app.state.view
    if isinstance(exc, Error):
        status, message, hint = _status_of(exc), str(exc).splitlines()[0], exc.hint
    elif isinstance(exc, HTTPException):
        status, message, hint = exc.status_code, str(exc.detail), None
    else:
        raise exc
    if request.url.path.startswith("/api/"):
        return JSONResponse({"error": message, "hint": hint, "status": status}, status_code=status)
    return view.page(
        request, "error.html", status_code=status, status=status, message=message, hint=hint, title="error"
    )


def home(request: Request) -> Response:
    return RedirectResponse("/classes", status_code=307)


def create_app(config: ViewConfig, *, hosts: Sequence[str] = ("127.0.0.1", "localhost")) -> Starlette:
    """The view's application for one database (serve it with uvicorn, as :func:`tgsis.view.serve` does).

    Parameters
    ----------
    config : ViewConfig
    hosts : sequence of str
        The ``Host`` names answered (others get 400: a page of another
        site cannot reach the view through a name of its own); every
        request but GET and HEAD must come from the view's own origin
        (:class:`RequestGuard`).
    """
    app = Starlette(
        routes=[
            Route("/", home),
            Route("/classes", classes_page),
            Route("/versions", versions_page),
            Route("/session", choose_version, methods=["POST"]),
            Route("/scene", scene_page),
            Route("/compare", compare_page),
            Route("/conflicts", conflicts_page),
            Route("/api/mesh/{id}", mesh_endpoint),
            Route("/api/mesh/{id}/header", mesh_header_endpoint),
            Route("/api/compare/{id}", compare_endpoint),
            Route("/api/conflict/{id}", conflict_endpoint),
            Mount("/static", StaticFiles(directory=str(HERE / "static")), name="static"),
        ],
        middleware=[Middleware(RequestGuard, hosts=list(hosts))],
        exception_handlers={Error: error_page, HTTPException: error_page},
    )
    app.state.view = View(config)
    return app
