"""`tgsis class alter`: add, rename and drop properties of a class from the command line, all or nothing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.cli import main


def _class(dsn: str) -> tgsis.FeatureClass:
    with psycopg.connect(dsn) as conn:
        return tgsis.get_feature_class(conn, "faults")


def _faults(dsn: str, *, versioned: bool) -> int:
    with psycopg.connect(dsn) as conn:
        tgsis.create_feature_class(
            conn, "faults", "SURFACE", feature_properties={"release": "text"}, cell_properties={"azi": "float8"}
        )
        mesh = tgsis.Surface(
            np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]),
            np.array([[0, 1, 2]]),
            vertex_properties={"azi": np.array([10.0, 20, 30])},
        )
        fid = tgsis.insert_feature(conn, "faults", mesh, {"release": "5.3"})
        if versioned:
            tgsis.enable_feature_versioning(conn)
        conn.commit()
    return fid


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_alter_adds_renames_and_drops(db_dsn: str, versioned: bool, capsys: pytest.CaptureFixture[str]) -> None:
    fid = _faults(db_dsn, versioned=versioned)
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "faults",
                "--add-property",
                "dip:float8=45",
                "--add-feature-property",
                "author:text=ann",
                "--rename-property",
                "azi",
                "azimuth",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert out.splitlines() == [
        "renamed property azi to azimuth",
        "added feature property author: 1 feature(s) got the default 'ann'",
        "added cell property dip: 3 vertex row(s) of 1 feature(s) got the default 45",
        "feature class faults: feature properties release text, author text; vertex properties azimuth double "
        "precision, dip double precision",
    ]
    with psycopg.connect(db_dsn) as conn:
        feature = tgsis.fetch_feature(conn, "faults", fid)
    assert feature.properties == {"release": "5.3", "author": "ann"} and isinstance(feature.mesh, tgsis.Mesh)
    assert feature.mesh.vertex_properties["azimuth"].tolist() == [10, 20, 30]
    assert feature.mesh.vertex_properties["dip"].tolist() == [45, 45, 45]
    # dropping stored values needs --force, in CLI words
    assert main(["--dsn", db_dsn, "class", "alter", "faults", "--drop-property", "dip"]) == 1
    err = capsys.readouterr().err
    assert "tgsis: error: cell property 'dip' of feature class faults holds 3 value(s)" in err
    assert "HINT: repeat with --force to delete its values" in err
    assert main(["--dsn", db_dsn, "class", "alter", "faults", "--drop-property", "cell:dip", "--force", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["changes"] == [{"op": "drop", "property": "dip", "kind": "cell"}]
    assert [p["name"] for p in document["properties"]] == ["azimuth"]
    assert [p["name"] for p in document["feature_properties"]] == ["release", "author"]


def test_one_bad_change_changes_nothing(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    _faults(db_dsn, versioned=True)
    before = _class(db_dsn)
    # the rename and the first addition would work; the second addition needs a value for the stored vertices
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "faults",
                "--rename-property",
                "azi",
                "azimuth",
                "--add-feature-property",
                "author:text",
                "--add-property",
                "dip:float8",
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert (
        "feature class faults has stored rows in faults_cellpros, which need a value of the new vertex property "
        "'dip'" in err
    )
    assert "HINT: give the value stored rows get: --add-property NAME:TYPE=VALUE" in err
    assert _class(db_dsn) == before
    for args, message in [
        (["--add-property", "dip"], "--add-property 'dip' must be NAME:TYPE"),
        (["--drop-property", "vertex:azi"], "must be NAME or KIND:NAME"),
        ([], "tgsis class alter needs a change"),
        (["--drop-property", "nope"], "feature class faults has no property 'nope'"),
        (["--add-feature-property", "release:text"], "has a feature property 'release' already"),
        (["--add-instant-property", "throw:float8"], "static feature class faults has no per-instant properties"),
    ]:
        assert main(["--dsn", db_dsn, "class", "alter", "faults", *args]) == 1, args
        assert message in capsys.readouterr().err, args
        assert _class(db_dsn) == before
    assert main(["--dsn", db_dsn, "class", "alter", "nope", "--drop-property", "x"]) == 1
    assert "HINT: `tgsis class list` shows the classes" in capsys.readouterr().err


def test_documented_example_runs(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "horizons", "SURFACE", cell_properties={"porosity": "float8"})
        conn.commit()
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "horizons",
                "--add-property",
                "permeability:float8=0",
                "--add-feature-property",
                "author:text",
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "horizons",
                "--rename-property",
                "porosity",
                "phi",
                "--drop-property",
                "author",
            ]
        )
        == 0
    )
    assert main(["--dsn", db_dsn, "class", "alter", "horizons", "--drop-property", "phi", "--force"]) == 0
    out = capsys.readouterr().out
    assert (
        out.splitlines()[-1] == "feature class horizons: feature properties -; vertex properties permeability "
        "double precision"
    )


def test_alter_says_how_many_rows_got_the_default(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    """What was stored, truthfully: how many rows got the default (none in an empty class, where the default is
    not kept), counted as the session's version reads them, and that the other versions' rows got it too."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "empty", "SURFACE", cell_properties={"azi": "float8"})
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "alter",
                "empty",
                "--add-property",
                "porosity:float8=0.2",
                "--add-feature-property",
                "basin:text=Paris Basin",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == [
        "added feature property basin: no stored rows, none got the default 'Paris Basin' (it is "
        "not kept: new rows give their own values)",
        "added cell property porosity: no stored rows, none got the default 0.2 (it is not kept: "
        "new rows give their own values)",
    ]
    fid = _faults(db_dsn, versioned=True)
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_version(conn, "v1")
        with tgsis.in_version(conn, "v1"):
            tgsis.delete_feature(conn, "faults", fid)
    assert main(["--dsn", db_dsn, "--in", "v1", "class", "alter", "faults", "--add-property", "dip:float8=45"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == (
        "added cell property dip: 0 vertex row(s) of 0 feature(s) got the default 45 as version v1 reads them; "
        "every version's rows got it"
    )
    with psycopg.connect(db_dsn) as conn:
        feature = tgsis.fetch_feature(conn, "faults", fid)  # in DEFAULT, the feature's rows got it too
    assert isinstance(feature.mesh, tgsis.Mesh) and feature.mesh.vertex_properties["dip"].tolist() == [45, 45, 45]
