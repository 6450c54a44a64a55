"""The real GOCAD files of data/cfm (SCEC CFM, BSD 3-Clause, shipped with the repository), for tests."""

from __future__ import annotations

from pathlib import Path

import pytest

CFM = Path(__file__).resolve().parents[1] / "data" / "cfm"


def cfm(relative: str) -> Path:
    """Path of a CFM file; the test FAILS (never skips) when the data is missing."""
    path = CFM / relative
    if not path.is_file():
        pytest.fail(f"CFM test data missing: {path} (the repository ships data/cfm)")
    return path
