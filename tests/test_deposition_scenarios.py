"""The ``synsed`` and ``river`` scenarios deposit their units the way the design does (issue 37, part 2).

A unit deposited during an interval [t1, t2] starts at t1 as the surface
it lies on and thickens to its top at t2; a younger top never passes below
an older one. Checked on what SQL answers (``tgsis.surfaces_at``: the
snapshots any psql user gets) at many times, not on the Python objects the
scenario built: every unit deposited by then is there, none below an older
one, and each starts on the surface beneath.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.conninfo import make_conninfo

from tgsis.db.temporal import surfaces_at
from tgsis.mesh import Surface
from tgsis.scenarios import run_scenario
from tgsis.testing import TestServer

#: synsed: when each horizon first exists (C grows from B over [1, 2], D from C over [2, 3], E from D over [3, 4])
SYNSED_START = {"horizon A": 1.0, "horizon B": 1.0, "horizon C": 1.0, "horizon D": 2.0, "horizon E": 3.0}
#: river: unit 2 grows over [0, 1] on unit 1 and the basement, unit 3 over [2, 3] on unit 2 and the basement
RIVER_START = {"basement": 0.0, "unit 1": 0.0, "unit 2": 0.0, "unit 3": 2.0}


def _heights(surface: Surface, xy: np.ndarray) -> np.ndarray:
    """(p,) height of ``surface`` straight above or below each (x, y), NaN where it does not reach.

    Brute force over every triangle (the scenarios' meshes are small), so
    that the check does not share code with what it checks.
    """
    corners = surface.vertices[surface.cells]  # (m, 3, 3)
    a, b, c = corners[:, 0, :2], corners[:, 1, :2], corners[:, 2, :2]
    det = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])  # (m,)
    flat = np.abs(det) < 1e-12
    det = np.where(flat, 1.0, det)
    px, py = xy[:, None, 0], xy[:, None, 1]
    l1 = ((b[:, 1] - c[:, 1]) * (px - c[:, 0]) + (c[:, 0] - b[:, 0]) * (py - c[:, 1])) / det
    l2 = ((c[:, 1] - a[:, 1]) * (px - c[:, 0]) + (a[:, 0] - c[:, 0]) * (py - c[:, 1])) / det
    l3 = 1.0 - l1 - l2
    inside = (l1 >= -1e-9) & (l2 >= -1e-9) & (l3 >= -1e-9) & ~flat
    z = l1 * corners[:, 0, 2] + l2 * corners[:, 1, 2] + l3 * corners[:, 2, 2]
    z = np.where(inside, z, np.nan)
    with np.errstate(all="ignore"):
        return np.asarray(
            np.nanmax(np.where(np.asarray(inside.any(axis=1))[:, None], z, -np.inf), axis=1) if len(xy) else np.zeros(0)
        )


def _below(younger: Surface, older: Surface) -> float:
    """How far the younger surface's vertices lie below the older surface (≤ 0: never below)."""
    under = _heights(older, younger.vertices[:, :2])
    reached = np.isfinite(under)
    return float((under[reached] - younger.vertices[reached, 2]).max(initial=-np.inf))


def _snapshots(dsn: str, feature_class: str, times: np.ndarray) -> dict[float, dict[str, Surface]]:
    with psycopg.connect(dsn) as conn:
        return {float(t): {s.name or "": s for s in surfaces_at(conn, feature_class, float(t)).values()} for t in times}


@pytest.fixture(scope="module")
def scenarios(pg: TestServer, tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """Both scenarios run once (small) on the test server: their reports and figures."""
    ran: dict[str, Any] = {}
    with pg.database("tgsis_dep") as (_, dsn):
        for name in ("synsed", "river"):
            lines: list[str] = []
            result = run_scenario(name, dsn, out=lines.append, folder=tmp_path_factory.mktemp(name))
            ran[name] = {
                "out": "\n".join(lines),
                "figures": result.figures,
                "dsn": make_conninfo(dsn, dbname=f"tgsis_demo_{name}"),
                "files": result.files,
            }
        yield ran


SYNSED_TIMES = np.round(np.arange(1.0, 4.51, 0.125), 3)
RIVER_TIMES = np.round(np.arange(0.0, 5.51, 0.125), 3)


@pytest.mark.parametrize(
    ("name", "feature_class", "starts", "times"),
    [
        ("synsed", "structure", SYNSED_START, SYNSED_TIMES),
        ("river", "river", RIVER_START, RIVER_TIMES),
    ],
)
def test_every_deposited_unit_is_there_at_every_time_after_its_start(
    scenarios: dict[str, Any], name: str, feature_class: str, starts: dict[str, float], times: np.ndarray
) -> None:
    at = _snapshots(scenarios[name]["dsn"], feature_class, times)
    missing = {t: sorted(u for u, start in starts.items() if start <= t and u not in found) for t, found in at.items()}
    assert {t: m for t, m in missing.items() if m} == {}
    early = {t: sorted(u for u, start in starts.items() if t < start and u in found) for t, found in at.items()}
    assert {t: e for t, e in early.items() if e} == {}


@pytest.mark.parametrize(
    ("name", "feature_class", "starts", "times"),
    [
        ("synsed", "structure", SYNSED_START, SYNSED_TIMES),
        ("river", "river", RIVER_START, RIVER_TIMES),
    ],
)
def test_no_younger_top_passes_below_an_older_one(
    scenarios: dict[str, Any], name: str, feature_class: str, starts: dict[str, float], times: np.ndarray
) -> None:
    at = _snapshots(scenarios[name]["dsn"], feature_class, times)
    order = list(starts)  # oldest first
    worst: dict[str, float] = {}
    for found in at.values():
        for i, younger in enumerate(order):
            for older in order[:i]:
                if younger in found and older in found:
                    key = f"{younger} under {older}"
                    worst[key] = max(worst.get(key, -np.inf), _below(found[younger], found[older]))
    crossing = {k: round(v, 4) for k, v in worst.items() if v > 0.01}
    assert crossing == {}


@pytest.mark.parametrize(
    ("name", "feature_class", "grown"),
    [
        (
            "synsed",
            "structure",
            {
                "horizon C": ("horizon B", 1.0, 2.0),
                "horizon D": ("horizon C", 2.0, 3.0),
                "horizon E": ("horizon D", 3.0, 4.0),
            },
        ),
        ("river", "river", {"unit 2": (None, 0.0, 1.0), "unit 3": (None, 2.0, 3.0)}),
    ],
)
def test_a_new_unit_starts_on_the_surface_beneath_and_thickens(
    scenarios: dict[str, Any], name: str, feature_class: str, grown: dict[str, tuple[str | None, float, float]]
) -> None:
    """At its start a unit lies on the surface beneath (the highest older one); it thickens to its top."""
    for unit, (beneath, t1, t2) in grown.items():
        times = np.linspace(t1, t2, 9)
        at = _snapshots(scenarios[name]["dsn"], feature_class, times)
        thickness = []
        for t in times:
            found = at[float(t)]
            top = found[unit]
            older = [
                found[n]
                for n in found
                if n != unit and (beneath is None or n == beneath) and (name != "river" or n < unit)
            ]
            floor = np.nanmax(np.stack([_heights(s, top.vertices[:, :2]) for s in older]), axis=0)
            assert np.isfinite(floor).all(), (unit, t)  # something lies under every vertex
            thickness.append(top.vertices[:, 2] - floor)
        assert np.abs(thickness[0]).max() < 1e-6, unit  # starts as the surface beneath
        means = [float(np.mean(h)) for h in thickness]
        assert all(b > a for a, b in zip(means, means[1:])), (unit, means)  # and thickens
        assert means[-1] > 10.0


def test_synsed_structure_at_2_5_from_sql_shows_horizon_d(scenarios: dict[str, Any]) -> None:
    out = scenarios["synsed"]["out"]
    answer = re.search(r"-> surface, vertices, triangles: (.*)", out)
    assert answer is not None
    assert [row.split(", ")[0] for row in answer.group(1).split("; ")] == [
        "fault F",
        "horizon A",
        "horizon B",
        "horizon C",
        "horizon D",
    ]
    assert scenarios["synsed"]["figures"]["structure_at_2.5"] == [
        "fault F",
        "horizon A",
        "horizon B",
        "horizon C",
        "horizon D",
    ]
    assert scenarios["synsed"]["figures"]["sql_equals_python"] is True


def test_river_structure_at_1_5_and_2_5_from_sql(scenarios: dict[str, Any]) -> None:
    figures = scenarios["river"]["figures"]
    assert figures["structure_at_1.5"] == ["basement", "unit 1", "unit 2"]
    assert figures["structure_at_2.5"] == ["basement", "unit 1", "unit 2", "unit 3"]
    assert figures["sql_equals_python"] is True


def test_the_contacts_are_reported(scenarios: dict[str, Any]) -> None:
    """Where a younger top would pass below an older one it is put on it, and the report says where and how far."""
    figures = scenarios["river"]["figures"]
    contact = figures["onlap_contact"]
    assert set(contact) == {"unit 1", "unit 2", "unit 3"}
    assert contact["unit 1"]["on"] == ["basement"]  # its pinch-outs
    assert "basement" in contact["unit 3"]["on"]  # its eastern pinch-out
    assert 0.0 <= figures["dip_between_instants_m"] <= 0.01
    for unit, found in contact.items():
        assert found["raised_m"] >= 0 and found["vertex_instants"] >= 0
        assert (
            f"{unit} on {', '.join(found['on'])}, raised {found['vertex_instants']} vertex-instants by at most "
            f"{found['raised_m']:g} m"
        ) in scenarios["river"]["out"]
