"""What the ``tgsis`` command remembers between runs: the working version per database.

``tgsis version goto NAME`` stores it; every later command on the same
database starts in that version. The file is ``$TGSIS_HOME/cli-state.json``
when ``TGSIS_HOME`` is set, else ``$XDG_CONFIG_HOME/tgsis/cli-state.json``
(``~/.config`` by default). No database here.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any


def state_file() -> Path:
    """Where the command's state is kept."""
    if home := os.environ.get("TGSIS_HOME"):
        return Path(home) / "cli-state.json"
    config = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(config) / "tgsis" / "cli-state.json"


def _load() -> dict[str, Any]:
    try:
        data = json.loads(state_file().read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return {}
    return data if isinstance(data, dict) else {}


def remembered_version(database: str) -> str | None:
    """The working version remembered for ``database`` (a connection target key), or None."""
    entry = _load().get("versions", {}).get(database)
    return entry if isinstance(entry, str) else None


def remember_version(database: str, version: str | None) -> None:
    """Remember ``version`` for ``database`` (None or DEFAULT: forget it). Written atomically."""
    data = _load()
    versions = data.setdefault("versions", {})
    if version is None or version == "DEFAULT":
        versions.pop(database, None)
    else:
        versions[database] = version
    path = state_file()
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False, suffix=".tmp") as tmp:
        json.dump(data, tmp, indent=2, sort_keys=True)
    os.replace(tmp.name, path)
