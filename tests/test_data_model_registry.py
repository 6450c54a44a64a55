"""The Python registry of data models (tgsis.datamodels) is the SQL one, and a new model needs nothing else (issue 38, part 1).

Found: following docs/developing.md to add a model meant editing hand lists
of models in db/features.py (the hand-off by type), db/classes.py (two
Literals), the CLI, the browser and the tests. Now ``insert_feature`` and
``fetch_object`` hand a feature to the model that stores it through the
registry, and the last test adds a throwaway model 9 the documented way (SQL
rows + one Python module) and drives a feature of it through the public API.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, get_args

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.test_model_registry import TEST_MODEL
from tgsis import datamodels
from tgsis.db.classes import FeatureClass
from tgsis.drawing import Drawable, drawable
from tgsis.errors import InvalidInputError, NotFoundError

Conn = psycopg.Connection[Any]


def test_the_python_registry_is_the_sql_registry(conn: Conn) -> None:
    rows = conn.execute(
        "SELECT model, name, timemodel, geotypes FROM tgsis.data_models WHERE model > 0 ORDER BY model"
    ).fetchall()
    assert [(m.number, m.name, m.time_model, list(m.geotypes)) for m in tgsis.data_models()] == [
        (int(r[0]), r[1], r[2], r[3]) for r in rows
    ]


def test_the_time_model_type_names_the_registered_models() -> None:
    assert list(get_args(datamodels.TimeModel)) == [m.time_model for m in tgsis.data_models()]
    assert set(get_args(datamodels.StoredObject)) == {t for m in tgsis.data_models() for t in m.types}
    from tgsis.db import features

    assert features.insert_feature.__annotations__["mesh"] in ("StoredObject", datamodels.StoredObject)
    from tgsis.db import classes

    for function in (classes.create_feature_class,):
        assert function.__annotations__["time_model"] in ("TimeModel", datamodels.TimeModel)
    assert FeatureClass.__annotations__["time_model"] in ("TimeModel", datamodels.TimeModel)


def test_every_shipped_model_has_its_database_functions() -> None:
    # in a fresh interpreter: no module lists the database modules, each entry names its own, loaded on first use
    program = (
        "import sys, tgsis.datamodels as d; assert 'tgsis.db' not in sys.modules\n"
        "for m in d.data_models():\n"
        "    s = d.storage_of(m); assert callable(s.insert) and callable(s.fetch), m\n"
        "    assert s.insert.__module__ == m.module, (m, s.insert.__module__)\n"
        "    assert s.draw is not None and s.draw.__module__ == m.module, (m, 'the view draws it')\n"
        "    assert all(h.__module__ == m.module for h in (s.life, s.colours, s.surface) if h is not None), m\n"
        "print(sorted(n for n in sys.modules if n.startswith('tgsis.db.') and n in "
        "{'tgsis.db.features', 'tgsis.db.instants', 'tgsis.db.evolving', 'tgsis.db.gmaps', 'tgsis.db.multidim'}))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == (
        "['tgsis.db.evolving', 'tgsis.db.features', 'tgsis.db.gmaps', 'tgsis.db.instants', 'tgsis.db.multidim']"
    )


def test_each_model_has_a_database_module_of_its_own() -> None:
    # issue 38, part 6: db/temporal.py held models 2 and 3, db/gmaps.py models 4 and 5; a change to one model
    # meant a file of two. Each entry names its own module, and that module's functions are the model's storage.
    modules = {m.number: m.module for m in tgsis.data_models()}
    assert modules == {
        1: "tgsis.db.features",
        2: "tgsis.db.instants",
        3: "tgsis.db.evolving",
        4: "tgsis.db.gmaps",
        5: "tgsis.db.multidim",
    }
    for model in tgsis.data_models():
        storage = datamodels.storage_of(model)
        assert (storage.insert.__module__, storage.fetch.__module__) == (model.module, model.module), model


def test_a_clashing_entry_is_refused() -> None:
    with pytest.raises(InvalidInputError, match="clashes with the registered model 2"):
        datamodels.register_data_model(datamodels.DataModel(9, "x", "INSTANTS", ("SURFACE",)))
    with pytest.raises(InvalidInputError, match="upper case"):
        datamodels.register_data_model(datamodels.DataModel(9, "x", "steps", ("MULTIPOINT",)))
    with pytest.raises(InvalidInputError, match="no Python module registered the data model of time model 'nope'"):
        datamodels.data_model("nope")


def test_an_object_no_model_stores_is_still_converted_or_refused(conn: Conn) -> None:
    fc = tgsis.create_feature_class(conn, "tops", "SURFACE")
    with pytest.raises(tgsis.Error):
        tgsis.insert_feature(conn, fc, object())  # type: ignore[arg-type]  # what a user may pass
    with pytest.raises(tgsis.InvalidInputError, match="has time model STATIC, not INSTANTS"):
        tgsis.insert_feature(
            conn, fc, tgsis.SurfaceSeries([0.0], [tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])])
        )


def test_fetch_object_reads_a_feature_of_every_shipped_model_as_it_was_stored(conn: Conn) -> None:
    from tests.temporal_data import evolving, series
    from tgsis import gmaps

    rng = np.random.default_rng(38)
    surface = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="tri")
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    lifted = gmaps.GMap.from_triangles([[0, 0, 0, 0.5], [1, 0, 0, 0.5], [1, 1, 0, 0.5]], [[0, 1, 2]])
    stored: dict[str, object] = {
        "STATIC": surface,
        "INSTANTS": series(rng, [0.0, 1.0, 2.0]),
        "EVOLVING": evolving(rng, [0.0, 2.0]),
        "GMAP": square,
        "MULTIDIM": lifted,
    }
    assert set(stored) == {m.time_model for m in tgsis.data_models()}
    for time_model, obj in stored.items():
        geotype = "GMAP" if isinstance(obj, gmaps.GMap) else "SURFACE"
        fc = tgsis.create_feature_class(
            conn,
            time_model.lower(),
            geotype,
            time_model=time_model,  # type: ignore[arg-type]
            cell_level=2 if geotype == "GMAP" else None,
        )
        fid = tgsis.insert_feature(conn, fc, obj)  # type: ignore[arg-type]
        back = tgsis.fetch_object(conn, fc.name, fid)
        if time_model == "STATIC":
            assert isinstance(back, tgsis.Surface)
            np.testing.assert_array_equal(back.vertices, surface.vertices)
        elif time_model == "INSTANTS":
            assert isinstance(back, tgsis.SurfaceSeries) and back.times.tolist() == [0.0, 1.0, 2.0]
        elif time_model == "EVOLVING":
            assert isinstance(back, tgsis.EvolvingSurface) and [p.times[0] for p in back.periods] == [0.0, 2.0]
        elif time_model == "GMAP":  # a plain G-map is one period of model 4
            assert isinstance(back, tgsis.EvolvingGMap) and back.at(0.0).same_as(square)  # type: ignore[union-attr]
        else:
            assert isinstance(back, tgsis.GMap) and back.same_as(lifted)
        with pytest.raises(NotFoundError):
            tgsis.fetch_object(conn, fc, fid + 1000)


# ---- a throwaway model 9: the SQL of tests/test_model_registry.py and this "module" -------------------------


@dataclass
class StepPoints:
    """Model 9's object: x values of points (the test model stores x only)."""

    x: npt.NDArray[np.float64]
    name: str | None = None


def insert_steps(
    conn: Conn,
    fc: FeatureClass,
    obj: StepPoints,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
) -> int:
    values = dict(properties or {})
    with conn.transaction():
        row = conn.execute(
            "SELECT tgsis.new_geometry('MULTIPOINT', %s, NULL, 0, 0, p_timemodel => 'STEPS', p_class => %s)",
            (name if name is not None else obj.name, fc.name),
        ).fetchone()
        assert row is not None
        geoid = int(row[0])
        with conn.cursor().copy("COPY tgsis.test9_point (geoid, pid, x) FROM STDIN") as copy:
            for i, x in enumerate(obj.x.tolist()):
                copy.write_row((geoid, i, x))
        conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
        columns = ["_geoid", *values]
        conn.execute(
            sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
                fc.qualified(fc.featuretable),
                sql.SQL(", ").join(map(sql.Identifier, columns)),
                sql.SQL(", ").join(sql.Placeholder() * len(columns)),
            ),
            [geoid, *values.values()],
        )
    return geoid


def fetch_steps(conn: Conn, fc: FeatureClass, feature_id: int) -> StepPoints:
    row = conn.execute(
        sql.SQL("SELECT g.geoname FROM {} f JOIN tgsis.geometry g ON g.geoid = f._geoid WHERE f._geoid = %s").format(
            fc.qualified(fc.featuretable)
        ),
        (feature_id,),
    ).fetchone()
    if row is None:
        raise NotFoundError(f"feature class {fc.name} has no feature {feature_id}")
    x = [r[0] for r in conn.execute("SELECT x FROM tgsis.test9_point WHERE geoid = %s ORDER BY pid", (feature_id,))]
    return StepPoints(np.array(x, dtype=np.float64), row[0])


def draw_steps(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    t: float | None,
    /,
    *,
    colour: str | None = None,
    beside: Any = None,
) -> Drawable:
    """What the browser view draws of a model-9 feature: its points on the x axis (a colour: "x")."""
    steps = fetch_steps(conn, fc, feature_id)
    points = np.zeros((len(steps.x), 3))
    points[:, 0] = steps.x
    return drawable(tgsis.PointSet(points, vertex_properties={"x": steps.x}))


def colours_of_steps(conn: Conn, fc: FeatureClass, feature_id: int) -> list[str]:
    return ["x"]


@pytest.fixture
def model9(conn: Conn, monkeypatch: pytest.MonkeyPatch) -> Iterator[datamodels.DataModel]:
    """Model 9 in SQL (the recipe: its storage file's functions and rows) and in Python (its module's two calls)."""
    conn.execute(TEST_MODEL)
    assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (True,)
    conn.commit()
    for shipped in datamodels.data_models():  # their functions loaded before the registry is copied
        datamodels.storage_of(shipped)
    monkeypatch.setattr(datamodels, "_MODELS", dict(datamodels._MODELS))  # thrown away after the test
    monkeypatch.setattr(datamodels, "_STORAGE", dict(datamodels._STORAGE))
    model = datamodels.register_data_model(
        datamodels.DataModel(9, "test points in steps", "STEPS", ("MULTIPOINT",), (StepPoints,))
    )
    datamodels.register_storage(
        "STEPS", insert=insert_steps, fetch=fetch_steps, draw=draw_steps, colours=colours_of_steps
    )
    yield model


def test_a_new_model_is_stored_fetched_versioned_merged_and_deleted_through_the_public_api(
    conn: Conn, model9: datamodels.DataModel
) -> None:
    assert model9 in tgsis.data_models()
    test_the_python_registry_is_the_sql_registry(conn)  # the module's entry is its SQL row
    fc = tgsis.create_feature_class(
        conn,
        "stepped",
        "MULTIPOINT",
        time_model="STEPS",  # type: ignore[arg-type]
        feature_properties=[("label", "text")],
    )
    first = tgsis.insert_feature(
        conn,
        fc,
        StepPoints(np.array([2.5, 1.0]), "s1"),  # type: ignore[arg-type]
        {"label": "a"},
    )
    fetched = tgsis.fetch_object(conn, "stepped", first)
    assert isinstance(fetched, StepPoints) and fetched.name == "s1"
    np.testing.assert_array_equal(fetched.x, [2.5, 1.0])
    assert conn.execute(
        "SELECT timemodel, nvrtx, bbox::text FROM tgsis.geometry WHERE geoid = %s", (first,)
    ).fetchone() == ("STEPS", 2, "(1, 0, 0),(2.5, 0, 0)")
    # a static mesh is not a feature of it
    with pytest.raises(tgsis.InvalidGeometryError, match="holds STEPS surfaces"):
        tgsis.insert_feature(conn, fc, tgsis.PointSet([[0, 0, 0]]))

    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "field")
    with tgsis.in_version(conn, "field"):
        second = tgsis.insert_feature(conn, fc, StepPoints(np.array([7.0]), "s2"))  # type: ignore[arg-type]
        conn.commit()
        assert tgsis.fetch_object(conn, fc, second).x.tolist() == [7.0]
        assert tgsis.delete_feature(conn, fc, first)
        conn.commit()
        with pytest.raises(NotFoundError):
            tgsis.fetch_object(conn, fc, first)
    # DEFAULT does not see the version's changes ...
    assert tgsis.fetch_object(conn, fc, first).x.tolist() == [2.5, 1.0]
    with pytest.raises(NotFoundError):
        tgsis.fetch_object(conn, fc, second)
    # ... until it is merged
    assert tgsis.merge_version(conn, "field") > 0
    assert tgsis.fetch_object(conn, fc, second).x.tolist() == [7.0]
    with pytest.raises(NotFoundError):
        tgsis.fetch_object(conn, fc, first)
    assert conn.execute("SELECT count(*) FROM tgsis.test9_point WHERE geoid = %s", (first,)).fetchone() == (0,)

    # deleted in DEFAULT: its rows go with it
    assert tgsis.delete_feature(conn, fc, second)
    with pytest.raises(NotFoundError):
        tgsis.fetch_object(conn, fc, second)
    assert conn.execute("SELECT count(*) FROM tgsis.test9_point").fetchone() == (0,)
    assert not tgsis.delete_feature(conn, fc, second)


def test_a_new_model_is_viewed_through_its_registry_entry(
    conn: Conn, db_dsn: str, model9: datamodels.DataModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.view_helpers import get, running_view
    from tgsis.view.meshes import unpack

    fc = tgsis.create_feature_class(conn, "stepped", "MULTIPOINT", time_model="STEPS")  # type: ignore[arg-type]
    # far from the origin: the view sends float32 offsets from the box's middle, the real coordinates come back
    stored = np.array([2_500_000.25, 2_500_001.5, 2_499_998.75])
    first = tgsis.insert_feature(conn, fc, StepPoints(stored, "s1"))  # type: ignore[arg-type]
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "field")
    with tgsis.in_version(conn, "field"):
        second = tgsis.insert_feature(conn, fc, StepPoints(np.array([7.0, -3.0]), "s2"))  # type: ignore[arg-type]
        conn.commit()
    conn.commit()

    def mesh(query: str) -> tuple[dict[str, Any], npt.NDArray[np.float64], dict[str, Any]]:
        status, body, _ = get(f"{url}/api/mesh/{query}")
        assert status == 200, body[:300]
        header, arrays = unpack(body)
        return header, arrays["positions"].reshape(-1, 3) + np.asarray(header["origin"]), arrays

    with running_view(db_dsn) as url:
        header, positions, arrays = mesh(str(first))
        assert (header["kind"], header["class"], header["name"], header["t"]) == ("points", "stepped", "s1", None)
        assert (header["n_vertices"], header["n_cells"], header["properties"]) == (3, 0, ["x"])
        # the stored points, each where it was stored (float32 offsets: to the centimetre at 2.5e6)
        np.testing.assert_allclose(positions, np.column_stack([stored, np.zeros(3), np.zeros(3)]), atol=0.01)
        assert np.abs(positions[:, 0] - stored).max() < 0.01 and np.ptp(positions[:, 0]) == pytest.approx(2.75)
        # coloured by what the model's entry offers
        header, _, arrays = mesh(f"{first}?color=x")
        np.testing.assert_allclose(arrays["values"], stored.astype(np.float32))
        # in a version: what the version holds; DEFAULT does not have it
        header, positions, _ = mesh(f"{second}?v=field")
        np.testing.assert_allclose(positions, [[7.0, 0, 0], [-3.0, 0, 0]], atol=1e-5)
        assert get(f"{url}/api/mesh/{second}")[0] == 404
        # the scene page takes it (no time slider: the model has no life) and its colour
        status, body, _ = get(f"{url}/scene?ids={first}&color=x")
        assert status == 200, body[:300]
        assert get(f"{url}/scene?ids={first}&color=porosity")[0] == 400

        # a model whose entry gives no way to draw it: refused, naming the model, not drawn wrongly
        storage = datamodels._STORAGE["STEPS"]
        monkeypatch.setitem(datamodels._STORAGE, "STEPS", datamodels.Storage(storage.insert, storage.fetch))
        for path in (f"/api/mesh/{first}", f"/scene?ids={first}"):
            status, body, _ = get(f"{url}{path}")
            assert status == 400 and b"data model 9 (STEPS)" in body, body[:300]


def test_a_model_without_its_python_module_is_named(conn: Conn) -> None:
    conn.execute(TEST_MODEL)
    conn.execute("SELECT tgsis.create_storage()")
    fc = tgsis.create_feature_class(conn, "stepped", "MULTIPOINT", time_model="STEPS")  # type: ignore[arg-type]
    conn.commit()
    with pytest.raises(InvalidInputError, match="no Python module registered the data model of time model 'STEPS'"):
        tgsis.fetch_object(conn, fc, 1)
