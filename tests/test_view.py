"""The browser view (issue 21) in a real browser: every page loads, the scenes draw, the DOM lists what the database holds.

Headless Chromium of the distribution (one for the module) against the view
served in a thread on one database of the module: classes and features with
their filters; the 3D scene drawn (not blank) and redrawn when the time slider
moves; the version tree and choosing a version; two versions compared (the
picture changes with the version); a version's conflicts on the mesh; bad
URLs answered with an error page and the message.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import tgsis
import tgsis.view
from tests.view_helpers import (
    QUOTED_NAME,
    ViewData,
    canvas_pixels,
    changed_fraction,
    chromium,
    drawn_fraction,
    fill_view_database,
    running_view,
    wait_drawn,
    watched_page,
)
from tgsis.testing import TestServer


@pytest.fixture(scope="module")
def view(pg: TestServer, template_db: str) -> Iterator[tuple[str, ViewData, str]]:
    with pg.database("tgsis_view", template_db) as (_, dsn):
        data = fill_view_database(dsn)
        with running_view(dsn) as url:
            yield url, data, dsn


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    with watched_page(browser, 1100, 900) as page:
        yield page


def _cells(page: Any, selector: str) -> list[str]:
    return [t.strip() for t in page.locator(selector).all_text_contents()]


def test_the_classes_page_lists_the_classes_and_features_the_database_holds(
    view: tuple[str, ViewData, str], page: Any
) -> None:
    url, data, _ = view
    response = page.goto(f"{url}/classes")
    assert response.status == 200
    assert page.locator("#classes tbody tr").evaluate_all("rows => rows.map(r => r.dataset.class)") == [
        "blocks",
        "horizons",
        "layers",
        "moving",
        "secret",
    ]
    assert page.locator("#classes tr[data-class=horizons] td.count").text_content() == "3"
    assert page.locator("#classes tr[data-class=moving]").text_content().count("EVOLVING") == 1
    assert "porosity:double precision (vertex)" in page.locator("#classes tr[data-class=horizons]").text_content()
    ids = [int(i) for i in page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")]
    assert sorted(ids) == sorted([data.top, data.base, data.quoted, data.block, data.moving, data.layers, data.hidden])
    assert page.locator("#classes tr[data-class=layers]").text_content().count("INSTANTS") == 1
    # a name with quotes and markup is shown as text, not markup
    assert page.locator(f"#features tr[data-id='{data.quoted}'] td.name").text_content() == QUOTED_NAME
    assert "-10 to 0" in page.locator(f"#features tr[data-id='{data.moving}']").text_content()

    page.goto(f"{url}/classes?class=horizons&name=O%27BRIEN")
    assert _cells(page, "#features tbody tr td.name") == [QUOTED_NAME]
    page.goto(f"{url}/classes?bbox=-1,-1,-8,30,30,-3")  # meets the base (z around -6) only, and the moving one
    ids = [int(i) for i in page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")]
    assert data.base in ids and data.top not in ids and data.quoted not in ids


def test_a_scene_draws_a_surface_and_a_property_colours_it(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.top}")
    wait_drawn(page)
    assert page.text_content("#status").startswith("400 vertices, 722 cells")
    assert page.get_attribute("#compare-link", "href") == f"/compare?id={data.top}&a=DEFAULT&b=DEFAULT"
    by_height = canvas_pixels(page)
    assert drawn_fraction(by_height) > 0.05
    page.select_option("#color", "porosity")
    wait_drawn(page, 2)
    assert "colour: porosity" in page.text_content("#status")
    assert changed_fraction(by_height, canvas_pixels(page)) > 0.02
    before = canvas_pixels(page)
    page.locator("#exaggeration").fill("10")
    page.wait_for_timeout(200)
    assert changed_fraction(before, canvas_pixels(page)) > 0.02


def test_several_features_and_a_tetrahedral_mesh_in_one_scene(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/classes")
    for fid in (data.base, data.block):
        page.check(f"#features input[value='{fid}']")
    page.click("#show-selected")
    wait_drawn(page)
    # the cube of 5 tetrahedra: 8 corners; its boundary: 12 triangles
    assert page.text_content("#status").startswith(f"{400 + 8} vertices, {722 + 12} cells")
    assert drawn_fraction(canvas_pixels(page)) > 0.02


def test_the_time_slider_shows_the_sql_snapshot_at_each_time(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.moving},{data.base}&t=-10")
    wait_drawn(page)
    assert page.text_content("#status").startswith("t = -10: ")
    at_start = canvas_pixels(page)
    assert drawn_fraction(at_start) > 0.02
    page.locator("#time").fill("0")
    wait_drawn(page, 2)
    assert page.text_content("#status").startswith("t = 0: ")
    assert "t=0" in page.url
    assert changed_fraction(at_start, canvas_pixels(page)) > 0.01


def test_the_time_slider_over_surfaces_at_instants(view: tuple[str, ViewData, str], page: Any) -> None:
    # model 2: the step convention takes the instant at or before t; a static feature stays in the scene
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.layers},{data.base}&t=-5")
    wait_drawn(page)
    assert page.text_content("#status").startswith(f"t = -5: {100 + 400} vertices")
    flat = canvas_pixels(page)
    page.locator("#time").fill("-3")
    wait_drawn(page, 2)
    assert page.text_content("#status").startswith("t = -3: ")
    assert changed_fraction(flat, canvas_pixels(page)) < 0.001  # still the instant -5
    page.locator("#time").fill("-1")
    wait_drawn(page, 3)
    assert changed_fraction(flat, canvas_pixels(page)) > 0.01  # the dome


def test_a_scene_of_features_with_different_lives(view: tuple[str, ViewData, str], page: Any) -> None:
    # the slider spans both lives; a feature is left out where it does not exist
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.moving},{data.layers}&t=-8")
    wait_drawn(page)
    assert page.get_attribute("#time", "min") == "-10.0" and page.get_attribute("#time", "max") == "0.0"
    assert page.text_content("#status").startswith("t = -8: 144 vertices")
    assert f"not there at t: {data.layers}" in page.text_content("#status")
    page.locator("#time").fill("-2")
    wait_drawn(page, 2)
    assert page.text_content("#status").startswith(f"t = -2: {144 + 100} vertices")


def test_the_version_tree_and_choosing_the_version(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/versions")
    assert page.locator("#versions tbody tr").evaluate_all("rows => rows.map(r => r.dataset.version)") == [
        "DEFAULT",
        "edit",
    ]
    row = page.locator("#versions tr[data-version=edit]").text_content()
    assert "DEFAULT" in row and "the top lifted in the west" in row
    assert page.text_content("#current") == "DEFAULT"
    page.click("#versions tr[data-version=edit] button.choose")
    assert page.text_content("#current") == "edit"
    assert page.text_content("#chosen-version") == "edit"
    page.goto(f"{url}/classes")
    assert "In version edit" in page.text_content("main")
    # an unknown revision is refused with an error page, and the choice stays
    # (page.request sends no Origin of its own: it is given the view's, as the page's own form sends it)
    response = page.request.post(f"{url}/session", form={"version": "edit@9999"}, headers={"Origin": url})
    assert response.status == 404 and "9999" in response.text()
    page.goto(f"{url}/versions")
    assert page.text_content("#current") == "edit"


def test_two_versions_compared_side_by_side_and_by_displacement(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/compare?id={data.top}&a=DEFAULT&b=DEFAULT")
    wait_drawn(page)
    assert page.locator("#changes td[data-key=vertices_added]").text_content() == "0"
    assert page.evaluate("document.body.dataset.highlighted") == "0"
    same = canvas_pixels(page)
    page.goto(f"{url}/compare?id={data.top}&a=DEFAULT&b=edit")
    wait_drawn(page)
    assert int(page.locator("#changes td[data-key=vertices_added]").text_content()) > 0
    assert int(page.evaluate("document.body.dataset.highlighted")) > 0
    marked = canvas_pixels(page)
    assert changed_fraction(same, marked) > 0.01
    page.uncheck("#marks")  # the dots off: the displacement colours alone
    assert changed_fraction(marked, canvas_pixels(page)) > 0.001
    page.goto(f"{url}/compare?id={data.top}&a=DEFAULT&b=edit&mode=side")
    wait_drawn(page)
    left, right = (int(n) for n in page.evaluate("document.body.dataset.highlighted").split(","))
    assert left > 0 and right > 0
    pixels = canvas_pixels(page)
    half = pixels.shape[1] // 2
    assert drawn_fraction(pixels[:, :half]) > 0.02 and drawn_fraction(pixels[:, half:]) > 0.02


def test_the_conflicts_of_a_version_on_the_mesh(view: tuple[str, ViewData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/conflicts?version=edit")
    wait_drawn(page)
    assert page.locator("#conflicts tbody tr").evaluate_all("rows => rows.map(r => r.dataset.key)") == [str(data.top)]
    unchanged, child, parent, both = (int(n) for n in page.evaluate("document.body.dataset.flags").split(","))
    assert child > 0 and parent > 0 and unchanged > 0
    assert drawn_fraction(canvas_pixels(page)) > 0.02


@pytest.mark.parametrize(
    ("path", "status", "message"),
    [
        ("/scene?ids=987654", 404, "no feature 987654"),
        ("/scene?ids=1%27%3B%20DROP%20TABLE%20x", 400, "is not a feature id"),
        ("/scene?ids=99999999999999999999", 400, "is not a feature id"),
        ("/scene?ids={moving}&t=50", 400, "outside the life"),
        ("/scene?ids={moving}&t=inf", 400, "not a finite number"),
        ("/scene?ids={top}&color=nope%27", 400, "colour"),
        ("/classes?class=x%27%22", 404, "no feature class"),
        ("/classes?bbox=1,2,3", 400, "bbox"),
        ("/compare?id={top}&a=DEFAULT&b=no%27pe", 404, "does not exist"),
        ("/compare?id={moving}&a=DEFAULT&b=edit", 400, "not a surface the view compares between versions"),
        ("/compare?id={block}&a=DEFAULT&b=edit", 400, "(class blocks: MULTITETRA, STATIC) is not a surface"),
        ("/conflicts?version=DEFAULT", 400, "no parent"),
        ("/conflicts?version=%27x", 404, "no version"),
        ("/api/mesh/{moving}?t=nan", 400, "not a finite number"),
        ("/api/mesh/abc", 400, "is not a feature id"),
    ],
)
def test_bad_urls_get_an_error_page_with_the_message(
    view: tuple[str, ViewData, str], page: Any, path: str, status: int, message: str
) -> None:
    url, data, _ = view
    response = page.goto(url + path.format(top=data.top, moving=data.moving, block=data.block))
    assert response.status == status
    if path.startswith("/api/"):
        assert message in response.json()["error"]
    else:
        assert message in page.text_content("#error-message")


def test_a_long_class_lists_its_first_features_and_says_so(
    view: tuple[str, ViewData, str], page: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    import tgsis.view.app

    url, data, _ = view
    monkeypatch.setattr(tgsis.view.app, "LISTED", 2)
    page.goto(f"{url}/classes?class=horizons")
    ids = [int(i) for i in page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")]
    assert ids == sorted([data.top, data.base, data.quoted])[:2]
    assert "horizons" in page.text_content("#truncated")
    page.goto(f"{url}/classes?class=blocks")
    assert page.locator("#truncated").count() == 0


def test_the_view_names_no_data_model_and_composes_no_sql() -> None:
    # how a feature is drawn is its data model's (the hooks of tgsis.datamodels, attached by the model's module);
    # storage, and the session's settings, are read and set through tgsis.db functions (issue 38)
    view = Path(tgsis.view.__file__).parent
    sources = {
        path.relative_to(view).as_posix(): path.read_text(encoding="utf-8")
        for path in sorted(view.rglob("*"))
        if path.suffix in (".py", ".html", ".js", ".css") and "vendor" not in path.parts
    }
    assert {"app.py", "meshes.py", "static/view.js", "templates/scene.html"} <= set(sources)
    for model in tgsis.data_models():
        assert [name for name, text in sources.items() if re.search(rf"\b{model.time_model}\b", text)] == [], model
    for pattern in (r"\.execute\(", r"\bpsycopg\.sql\b|from psycopg import sql", r"\btgsis\.\w+\(", r"\bSELECT\b"):
        assert [name for name, text in sources.items() if re.search(pattern, text)] == [], pattern
