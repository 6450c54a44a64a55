"""The manager's questions of a whole class: which features' per-instant property satisfies a condition, and when.

``tgsis.class_property_periods`` (SQL), :func:`tgsis.class_property_periods`
(Python) and ``tgsis query`` (CLI) must give, for every feature of a class,
exactly what :func:`tgsis.property_periods` gives for it alone, leave out
the features where the condition never holds, and refuse bad questions with
the per-feature function's errors (issue 18, part 2).
"""

from __future__ import annotations

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series
from tgsis.cli import main
from tgsis.cli._output import show_time

Conn = psycopg.Connection[object]


@pytest.fixture
def faults(db_dsn: str) -> dict[int, str]:
    """Four evolving faults with a per-instant throw, committed; their ids."""
    with psycopg.connect(db_dsn) as conn:
        fc = tgsis.create_feature_class(
            conn,
            "faults",
            "SURFACE",
            time_model="EVOLVING",
            time_unit="Ma",
            instant_properties=[("throw", "double precision"), ("note_code", "integer")],
        )
        ids = {}
        for seed in range(4):
            surface = evolving(np.random.default_rng(seed), [-10.0, -4.0], instants_per_period=4, with_properties=True)
            ids[tgsis.insert_feature(conn, fc, surface, drop_extra_properties=True)] = f"fault {seed}"
        tgsis.create_feature_class(
            conn,
            "horizons",
            "SURFACE",
            time_model="INSTANTS",
            instant_properties=[("throw", "double precision"), ("note_code", "integer")],
        )
        tgsis.create_feature_class(conn, "plain", "SURFACE")
        tgsis.insert_feature(
            conn,
            "horizons",
            series(np.random.default_rng(9), [0.0, 1.0, 2.0], with_properties=True),
            drop_extra_properties=True,
        )
    return ids


@pytest.mark.parametrize("op, value", [(">=", 50.0), ("<", 20.0), (">", 1000.0), ("<>", -1.0)])
def test_a_class_query_is_the_per_feature_question_for_each_feature(
    db_dsn: str, faults: dict[int, str], op: str, value: float
) -> None:
    with psycopg.connect(db_dsn) as conn:
        got = tgsis.class_property_periods(conn, "faults", "throw", op, value)
        expected = {fid: tgsis.property_periods(conn, "faults", fid, "throw", op, value) for fid in faults}
    assert got == {fid: periods for fid, periods in expected.items() if periods}
    if op == ">":
        assert got == {}  # never that large
    if op == "<>":
        assert set(got) == set(faults)  # always


def test_the_command_prints_each_feature_and_when(
    db_dsn: str, faults: dict[int, str], capsys: pytest.CaptureFixture[str]
) -> None:
    with psycopg.connect(db_dsn) as conn:
        expected = tgsis.class_property_periods(conn, "faults", "throw", ">=", 50.0)
    assert main(["--dsn", db_dsn, "query", "faults", "throw", ">=", "50"]) == 0
    header, *lines = capsys.readouterr().out.splitlines()
    assert header == "id\tperiods"
    assert lines == [f"{fid}\t" + " ".join(str(p) for p in periods) for fid, periods in expected.items()]
    assert main(["--dsn", db_dsn, "query", "faults", "throw", ">=", "50", "--first"]) == 0
    firsts = capsys.readouterr().out.splitlines()[1:]  # under the header line; times rounded for people
    assert [line.split("\t")[:2] for line in firsts] == [
        [str(fid), show_time(p[0].start)] for fid, p in expected.items()
    ]
    assert main(["--dsn", db_dsn, "query", "faults", "throw", ">", "1000"]) == 0
    assert "no feature of faults has throw > 1000.0 at any time" in capsys.readouterr().err


def test_bad_questions_are_refused_as_for_one_feature(db_dsn: str, faults: dict[int, str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        for args, error, message in [
            (("faults", "slip", ">", 1.0), tgsis.InvalidPropertyError, "has no per-instant property 'slip'"),
            (("faults", "throw", "~", 1.0), tgsis.InvalidInputError, "operator"),
            (("faults", "throw", ">", float("nan")), tgsis.InvalidInputError, "must be a number"),
            (("plain", "throw", ">", 1.0), tgsis.InvalidInputError, "static"),
            (("nope", "throw", ">", 1.0), tgsis.NotFoundError, "nope"),
        ]:
            with pytest.raises(error, match=message):
                tgsis.class_property_periods(conn, *args)
        # the same question of a model-2 class, by each step convention
        horizon = conn.execute("SELECT _geoid FROM horizons").fetchone()[0]  # type: ignore[index]
        for convention in ("left", "right"):
            got = tgsis.class_property_periods(conn, "horizons", "throw", "<", 101.0, convention=convention)
            assert got == {
                horizon: tgsis.property_periods(conn, "horizons", horizon, "throw", "<", 101.0, convention=convention)
            }
