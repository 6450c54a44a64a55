"""The data models on the Python side: one entry per row of ``tgsis.data_models``.

A data model is a unit (docs/developing.md, "A data model"): a folder in
``sql/`` whose storage file inserts its row into ``tgsis.data_models``, and,
here, one :class:`DataModel` entry naming the same number, time model and
geotypes plus the Python objects it stores. :func:`tgsis.insert_feature`
hands an object to the model that stores its type, :func:`tgsis.fetch_object`
reads a feature through the model of its class; neither types a list of
models.

This module is pure: it imports neither psycopg nor :mod:`tgsis.db`. The
database functions that store and read a model's objects are attached by the
database module of the model (:func:`register_storage`, called when that
module is imported; the entry names the module, which :func:`storage_of`
imports on first use), so that the numpy side can name the models without
loading the database layer. Deleting, versioning and merging need no
function of a model: SQL does them for every model from
``tgsis.model_tables``. The browser view (``tgsis view``) draws a feature
through the hooks the same module attaches beside them (:class:`Storage`:
``draw``, ``life``, ``colours``, ``surface``); it names no model itself.

A test (tests/test_data_model_registry.py) keeps these entries equal to the
rows of ``tgsis.data_models`` of a fresh database.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, get_args

from tgsis.errors import InvalidInputError
from tgsis.gmaps import EvolvingGMap, GMap
from tgsis.mesh import GeometryCollection, Mesh
from tgsis.temporal import EvolvingSurface, SurfaceSeries

__all__ = [
    "DataModel",
    "Storage",
    "StoredObject",
    "TimeModel",
    "data_models",
    "data_model",
    "model_storing",
    "register_data_model",
    "register_storage",
    "storage_of",
]

#: The objects the shipped data models store (their :attr:`DataModel.types`), for type checkers; a test keeps
#: it equal to the registry.
StoredObject = Mesh | GeometryCollection | SurfaceSeries | EvolvingSurface | EvolvingGMap | GMap

#: The time models of the shipped data models (``tgsis.data_models.timemodel``), for type checkers;
#: a test keeps it equal to the registry. A model added later is named by a plain ``str``.
TimeModel = Literal["STATIC", "INSTANTS", "EVOLVING", "GMAP", "MULTIDIM"]


class InsertFunction(Protocol):
    """Store ``obj`` as a new feature of the class ``fc`` in one transaction; return its id (geoid)."""

    def __call__(
        self,
        conn: Any,
        fc: Any,
        obj: Any,
        properties: Mapping[str, Any] | None = None,
        /,
        *,
        name: str | None = None,
        drop_extra_properties: bool = False,
    ) -> int: ...


#: Read feature ``feature_id`` of class ``fc`` back as the object the model stores: ``(conn, fc, feature_id)``.
FetchFunction = Callable[[Any, Any, int], Any]


class DrawFunction(Protocol):
    """What the browser view draws of feature ``feature_id`` of class ``fc``, as the session's version sees it.

    Returns a :class:`tgsis.drawing.Drawable`, or None when the feature
    does not exist at ``t``. ``t`` is a finite time inside or outside the
    feature's life for a model with a :attr:`Storage.life`, None for a model
    without time. ``colour``: the name of the vertex values to carry (one the
    model's :attr:`Storage.colours` offered), None for height only.
    ``beside``: a callable returning a context manager of a second connection
    that sees what ``conn`` sees (same snapshot and version), for reading two
    tables side by side; None when there is none.
    """

    def __call__(
        self,
        conn: Any,
        fc: Any,
        feature_id: int,
        t: float | None,
        /,
        *,
        colour: str | None = None,
        beside: Callable[[], Any] | None = None,
    ) -> Any: ...


#: The span of times the browser view's time slider covers for feature ``feature_id``: ``(conn, feature_id)`` ->
#: ``(first, last)``, None for a feature with no instant stored.
LifeFunction = Callable[[Any, int], tuple[float, float] | None]

#: What the browser view can colour feature ``feature_id`` of class ``fc`` by besides height: ``(conn, fc,
#: feature_id)`` -> names of vertex values its :data:`DrawFunction` carries.
ColoursFunction = Callable[[Any, Any, int], list[str]]

#: The stored surface the browser view compares between versions: ``(conn, fc, feature_id)`` -> a
#: :class:`tgsis.drawing.StoredSurface` (vertices and triangles with their stored ids).
SurfaceFunction = Callable[[Any, Any, int], Any]


@dataclass(frozen=True)
class DataModel:
    """A data model: the Python side of one row of ``tgsis.data_models``.

    Attributes
    ----------
    number : int
        ``tgsis.data_models.model`` (1: static objects, 2: surfaces at
        instants, 3: evolving surfaces, 4: G-maps in time, 5: multiply indexed
        G-maps; 0, the geometry core, stores no object of its own and has no
        entry here).
    name : str
        ``tgsis.data_models.name``.
    time_model : str
        ``tgsis.data_models.timemodel``: the ``time_model`` of its feature
        classes.
    geotypes : tuple of str
        ``tgsis.data_models.geotypes``: the geotypes of its classes.
    types : tuple of type
        The Python objects a feature of the model is stored from (a subclass
        counts): :func:`tgsis.insert_feature` gives an object of one of them
        to this model's :attr:`Storage.insert`.
    module : str or None
        The database module that attaches the model's :class:`Storage`
        (:func:`register_storage`); :func:`storage_of` imports it on first
        use, so no module lists the models' database modules.
    """

    number: int
    name: str
    time_model: str
    geotypes: tuple[str, ...]
    types: tuple[type, ...] = field(default=())
    module: str | None = None

    def stores(self, obj: object) -> bool:
        """Whether ``obj`` is an object this model stores."""
        return isinstance(obj, self.types)


@dataclass(frozen=True)
class Storage:
    """The database functions of a data model, attached by its database module.

    Attributes
    ----------
    insert : callable
        ``insert(conn, fc, obj, properties, *, name, drop_extra_properties) -> int``.
    fetch : callable
        ``fetch(conn, fc, feature_id)``: the stored object (one of the model's
        :attr:`DataModel.types`).
    draw : callable or None
        ``draw(conn, fc, feature_id, t, *, colour, beside)``: what the browser
        view draws of a feature (:class:`DrawFunction`); None: the view does
        not draw the model, and says so.
    life : callable or None
        ``life(conn, feature_id) -> (first, last) | None``: the times the
        view's slider covers; None: a model without time (drawn whole, ``t``
        ignored).
    colours : callable or None
        ``colours(conn, fc, feature_id) -> list[str]``: what the view colours
        a feature by besides height; None: the class's numeric vertex
        properties.
    surface : callable or None
        ``surface(conn, fc, feature_id)``: a surface feature as stored, with
        its vertex and triangle ids, for the view's comparison of two
        versions and its conflicts; None: the view does not compare the
        model's features.
    """

    insert: InsertFunction
    fetch: FetchFunction
    draw: DrawFunction | None = None
    life: LifeFunction | None = None
    colours: ColoursFunction | None = None
    surface: SurfaceFunction | None = None


_MODELS: dict[int, DataModel] = {}
_STORAGE: dict[str, Storage] = {}


def register_data_model(model: DataModel) -> DataModel:
    """Add the entry of a data model (its SQL folder inserts the matching ``tgsis.data_models`` row).

    Registering the same entry again is a no-op (a module imported twice);
    another entry with a number or time model already taken is refused.
    """
    if not isinstance(model, DataModel):
        raise InvalidInputError(f"a data model is a tgsis.DataModel, not a {type(model).__name__}")
    if model.time_model != model.time_model.upper():
        raise InvalidInputError(
            f"data model {model.number}: its time model {model.time_model!r} is upper case in tgsis.data_models",
            hint=f"time_model={model.time_model.upper()!r}",
        )
    for known in _MODELS.values():
        if known == model:
            return known
        if model.number == known.number or model.time_model == known.time_model:
            raise InvalidInputError(
                f"data model {model.number} ({model.time_model}) clashes with the registered "
                f"model {known.number} ({known.time_model})",
                hint="each data model has its own number and time model (tgsis.data_models)",
            )
    _MODELS[model.number] = model
    return model


def register_storage(
    time_model: str,
    *,
    insert: InsertFunction,
    fetch: FetchFunction,
    draw: DrawFunction | None = None,
    life: LifeFunction | None = None,
    colours: ColoursFunction | None = None,
    surface: SurfaceFunction | None = None,
) -> None:
    """Attach the database functions of a registered data model (called by its database module).

    ``draw``, ``life``, ``colours`` and ``surface`` are how the browser view
    shows the model's features (:class:`Storage`); a model without ``draw``
    is stored and read but not drawn.
    """
    data_model(time_model)  # a registered model
    _STORAGE[time_model.upper()] = Storage(insert, fetch, draw, life, colours, surface)


def data_models() -> list[DataModel]:
    """The registered data models, by number."""
    return [_MODELS[n] for n in sorted(_MODELS)]


def data_model(time_model: str) -> DataModel:
    """The data model of a time model (a feature class's ``time_model``; letter case ignored).

    Raises
    ------
    InvalidInputError
        No Python module registered the model (its SQL rows may exist).
    """
    wanted = time_model.upper()
    for model in _MODELS.values():
        if model.time_model == wanted:
            return model
    raise InvalidInputError(
        f"no Python module registered the data model of time model {time_model!r}",
        hint="import the module of the model (it calls tgsis.datamodels.register_data_model), "
        f"or use one of {', '.join(m.time_model for m in data_models())}",
    )


def model_storing(obj: object, time_model: str) -> DataModel | None:
    """The model that stores ``obj``: the one of ``time_model`` if it does, else the first (by number) that does.

    ``None`` when no model stores objects of its type.
    """
    models = [m for m in data_models() if m.stores(obj)]
    for model in models:
        if model.time_model == time_model.upper():
            return model
    return models[0] if models else None


def storage_of(model: DataModel) -> Storage:
    """The database functions of ``model``.

    Raises
    ------
    InvalidInputError
        Its database module has not attached them.
    """
    if model.time_model not in _STORAGE and model.module is not None:
        importlib.import_module(model.module)  # it registers its functions when imported
    try:
        return _STORAGE[model.time_model]
    except KeyError:
        raise InvalidInputError(
            f"data model {model.number} ({model.time_model}) has no database functions",
            hint="import the database module of the model (it calls tgsis.datamodels.register_storage)",
        ) from None


STATIC = register_data_model(
    DataModel(
        1,
        "static 3D objects",
        "STATIC",
        ("MULTIPOINT", "MULTILINESTRING", "SURFACE", "MULTITETRA", "GEOMETRYCOLLECTION"),
        (Mesh, GeometryCollection),
        "tgsis.db.features",
    )
)
INSTANTS = register_data_model(
    DataModel(2, "surfaces at instants", "INSTANTS", ("SURFACE",), (SurfaceSeries,), "tgsis.db.instants")
)
EVOLVING = register_data_model(
    DataModel(3, "continuously evolving surfaces", "EVOLVING", ("SURFACE",), (EvolvingSurface,), "tgsis.db.evolving")
)
GMAPS_IN_TIME = register_data_model(
    DataModel(4, "generalized maps in time", "GMAP", ("GMAP",), (EvolvingGMap, GMap), "tgsis.db.gmaps")
)
MULTIDIM = register_data_model(
    DataModel(5, "multiply indexed G-maps", "MULTIDIM", ("GMAP",), (GMap,), "tgsis.db.multidim")
)

assert set(get_args(TimeModel)) == {m.time_model for m in data_models()}, "TimeModel names the shipped models"
assert set(get_args(StoredObject)) == {t for m in data_models() for t in m.types}, "StoredObject: the shipped types"
