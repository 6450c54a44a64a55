"""The `tgsis` commands the documentation shows are accepted by the command line's parser.

README.md and docs/install.md showed ``tgsis db install --dsn ...``, which the
parser refuses (``--dsn`` is a global option, before the command). This test
parses every ``tgsis`` command of the ``sh`` blocks of the documentation
(optional ``[...]`` parts of a synopsis left out), and every inline command
that gives ``--dsn``.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from tgsis.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "docker" / "README.md"]


def _commands() -> list[tuple[str, str]]:
    """(file, command line) of every `tgsis` command shown."""
    found = []
    for path in DOCS:
        if not path.exists():
            continue
        text = path.read_text(encoding="utf-8")
        for block in re.findall(r"```(?:sh|bash|console)\n(.*?)```", text, re.S):
            for line in block.splitlines():
                for command in re.findall(r"(?:^|&&|\|\||;|\$\()\s*(tgsis\b[^#&;|)]*)", line):
                    found.append((path.name, re.sub(r"\s*\[[^\]]*\]", "", command).strip()))
        for span in re.findall(r"`(tgsis [^`]*--dsn[^`]*)`", text):
            found.append((path.name, span.replace("...", "x")))
    return found


COMMANDS = _commands()


def test_the_documentation_shows_commands() -> None:
    assert len(COMMANDS) > 20
    assert any("db install" in command and "--dsn" in command for _, command in COMMANDS)


@pytest.mark.parametrize("where, command", COMMANDS, ids=[f"{w}: {c}" for w, c in COMMANDS])
def test_documented_command_parses(where: str, command: str, capsys: pytest.CaptureFixture[str]) -> None:
    argv = shlex.split(command)[1:]
    try:
        build_parser().parse_args(argv)
    except SystemExit as exc:
        pytest.fail(
            f"{where} shows `{command}`, which the parser refuses (exit {exc.code}): {capsys.readouterr().err.strip()}"
        )
