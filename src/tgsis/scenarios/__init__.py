"""The sample applications of the specification, end to end: ``tgsis demo NAME``.

Each scenario makes its own geologically plausible data (deterministic),
stores it through the public API in a database of its own
(``tgsis_demo_<name>``, dropped first), asks its questions in SQL (printing
the statement, with its values, and the answer, for psql users to copy), and
writes pictures and a ParaView series into a folder. ``tgsis demo --list``
names them; ``cfm`` is the release story on the real faults
(:mod:`tgsis.demo`).

>>> from tgsis.scenarios import run_scenario               # doctest: +SKIP
>>> result = run_scenario("saltdome", folder="out")
>>> result.files                                           # pictures, GIF, .pvd
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from tgsis._optional import require
from tgsis.errors import InvalidInputError
from tgsis.scenarios._context import Context, Scenario, ScenarioResult, Size, open_context

__all__ = ["SCENARIOS", "Scenario", "ScenarioResult", "run_scenario"]


def _saltdome(context: Context) -> None:
    from tgsis.scenarios.saltdome import run

    run(context)


def _synsed(context: Context) -> None:
    from tgsis.scenarios.synsed import run

    run(context)


def _river(context: Context) -> None:
    from tgsis.scenarios.river import run

    run(context)


def _interpretations(context: Context) -> None:
    from tgsis.scenarios.interpretations import run

    run(context)


def _mine(context: Context) -> None:
    from tgsis.scenarios.mine import run

    run(context)


def _knowledge(context: Context) -> None:
    from tgsis.scenarios.knowledge import run

    run(context)


def _merge(context: Context) -> None:
    from tgsis.scenarios.merge import run

    run(context)


def _cfm(context: Context) -> None:
    raise AssertionError("cfm runs through tgsis.demo.run_demo")  # pragma: no cover - dispatched below


SCENARIOS: dict[str, Scenario] = {
    "saltdome": Scenario(
        "saltdome", "a flat salt layer rising into a dome: the shape at any time, from SQL and Python", _saltdome
    ),
    "synsed": Scenario(
        "synsed",
        "horizons deposited while a normal fault slips: the whole structure at t = 2.5 "
        "from one SQL query; older horizons carry more throw",
        _synsed,
    ),
    "river": Scenario(
        "river",
        "three units deposited and eroded on a fixed basement: the structure at t = 1.5, "
        "which unit lies on which at t = 3 and 4",
        _river,
    ),
    "interpretations": Scenario(
        "interpretations",
        "one horizon, several models in versions and named revisions: "
        "where the fault first appears, where dilatancy passes a threshold",
        _interpretations,
    ),
    "mine": Scenario(
        "mine",
        "a resource model revised after each survey: a chain of versions with validity periods, "
        "models as sets of objects; which model was believed on a date, what changed, rows stored",
        _mine,
    ),
    "knowledge": Scenario(
        "knowledge",
        "a horizon's interpretations as one object over a knowledge axis (model 5): "
        "box queries over x, y and knowledge, slices back to each interpretation",
        _knowledge,
    ),
    "merge": Scenario(
        "merge",
        "three geologists edit the two ends of one real CFM fault in three versions: disjoint edits merge "
        "by region, an overlapping one is a region conflict solved by average",
        _merge,
    ),
    "cfm": Scenario(
        "cfm", "the release story on real faults of the SCEC Community Fault Model (versions, check-in)", _cfm
    ),
}


def run_scenario(
    name: str,
    dsn: str | None = None,
    *,
    out: Callable[[str], None] = print,
    folder: str | Path | None = None,
    size: Size = "small",
) -> ScenarioResult:
    """Run scenario ``name`` on the server of ``dsn`` (``None``: the local server).

    Parameters
    ----------
    name : str
        One of :data:`SCENARIOS`.
    dsn : str, optional
        See :func:`tgsis.connect`; the scenario creates (and first drops) the
        database ``tgsis_demo_<name>`` there.
    out : callable
        Receives each line of the report.
    folder : str or path-like, optional
        Where its pictures and series go (created); default a new temporary folder.
    size : {"small", "large"}
        The size of the data it makes.

    Returns
    -------
    ScenarioResult
        The files written and the figures the report printed.
    """
    scenario = SCENARIOS.get(name)
    if scenario is None:
        raise InvalidInputError(f"no scenario {name!r}", hint=f"the scenarios: {', '.join(sorted(SCENARIOS))}")
    if size not in ("small", "large"):
        raise InvalidInputError(f"size must be 'small' or 'large', got {size!r}")
    if name == "cfm":
        from tgsis.demo import run_demo

        target = Path(folder) if folder is not None else None
        return ScenarioResult(name, run_demo(dsn, out=out, folder=target), {})
    # every scenario draws pictures: say so before it makes its database, not after
    require("matplotlib", f"tgsis demo {name} (its pictures)")
    with open_context(name, dsn, out=out, folder=folder, size=size) as context:
        scenario.run(context)
        out(f"summary: {context.summary_line()}")
        out(f"files in {context.folder}: {', '.join(p.name for p in context.files)}")
        return ScenarioResult(name, list(context.files), dict(context.figures))
