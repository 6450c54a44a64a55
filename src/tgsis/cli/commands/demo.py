"""``tgsis demo``: the sample applications."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from tgsis.cli._arguments import add_command
from tgsis.cli._output import out, print_table, render, wants_json
from tgsis.errors import (
    InvalidInputError,
)

if TYPE_CHECKING:
    from tgsis.scenarios import Scenario


def cmd_demo(args: argparse.Namespace) -> int:
    from tgsis.scenarios import SCENARIOS, run_scenario

    if args.list:
        return render(args, list(SCENARIOS.values()), scenarios_text, scenarios_json)
    if wants_json(args) or args.no_header:
        raise InvalidInputError("--json and --no-header go with --list", hint="tgsis demo --list --json")
    run_scenario(args.name, args.dsn, out=out, folder=args.dir, size=args.size)
    return 0


def scenarios_text(args: argparse.Namespace, scenarios: list[Scenario]) -> None:
    print_table(args, ("scenario", "shows"), [(s.name, s.summary) for s in scenarios])


def scenarios_json(scenarios: list[Scenario]) -> dict[str, Any]:
    return {"scenarios": [{"name": s.name, "summary": s.summary} for s in scenarios]}


def add_demo_parser(commands: Any) -> None:
    """``tgsis demo``."""
    demo = add_command(
        commands,
        "demo",
        "run a sample application end to end (default: cfm, the release story)",
        [
            "tgsis demo saltdome --dir out   # then look at out/*.png, out/saltdome.gif",
            "tgsis demo --list",
            "tgsis demo --list --json",
        ],
        cmd_demo,
        tabular=True,
    )
    demo.add_argument(
        "name",
        nargs="?",
        default="cfm",
        metavar="NAME",
        help="the scenario (tgsis demo --list names them; default: cfm)",
    )
    demo.add_argument("--list", action="store_true", help="list the scenarios and what each shows")
    demo.add_argument("--dir", metavar="DIR", help="folder for the files it writes (default: a new temporary folder)")
    demo.add_argument(
        "--size",
        choices=("small", "large"),
        default="small",
        help="how much data the scenario makes (default: small, under a minute)",
    )
