"""The ``tgsis`` command line (see docs/cli.md).

Every command that needs a database takes ``--dsn``; without it the database
comes from ``$TGSIS_DSN``, libpq's ``PG*`` variables, or the local server that
tgsis starts for the command and stops afterwards (``tgsis local start`` keeps
one running).

The package holds one module per command group under ``commands/`` (its parser
and its handlers), the shared plumbing in private modules (``_connection``:
database and version; ``_output``: text or ``--json``; ``_arguments``: argument
types and sub-command making), and ``_main`` (the parser and ``main``).
"""

from tgsis.cli._main import build_parser, main

__all__ = ["main", "build_parser"]
