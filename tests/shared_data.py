"""The real GOCAD files of ../shared/data/cfm (beside the repository), for tests."""

from __future__ import annotations

from pathlib import Path

import pytest

CFM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "cfm"


def cfm(relative: str) -> Path:
    """Path of a CFM file; the test FAILS (never skips) when the shared data is missing."""
    path = CFM / relative
    if not path.is_file():
        pytest.fail(f"shared CFM test data missing: {path} (the repository expects ../shared beside it)")
    return path
