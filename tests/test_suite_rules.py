"""Rules that keep the suite's wall time within CI's budget on both servers (docs/testing.md, "Wall time").

Before PostgreSQL 18 a plan node turned off (``enable_seqscan = off`` ...) adds 1e10 to the cost of every plan
that still needs it, far above ``jit_above_cost``: on a server built with JIT (Debian's PostgreSQL 15, the first
suite of ``make test``; the embedded 18 has no JIT) every query of the session is compiled, a few hundred
milliseconds each. One Hypothesis test that looked at the one-ring through the vertex BRIN so took 58 s on 15
and 2 s on 18. The functions of sql/ follow the same rule (tests/test_sql_sources.py); JIT itself stays tested
where a test asks for it (``jit = on`` with ``jit_above_cost = 0`` in tests/test_review_sql_regions.py).
"""

from __future__ import annotations

import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent

# a string literal that turns a plan node off: "SET enable_seqscan = off", "SET LOCAL enable_sort TO off", ...
_DISABLING = re.compile(r"""(["'])([^"'\n]*\benable_\w+\s*(?:=|\bTO\b)\s*off\b[^"'\n]*)\1""", re.I)


def disabling_without_jit_off(text: str) -> list[str]:
    """The string literals of ``text`` that turn a plan node off without turning JIT off in the same string."""
    return [m.group(2) for m in _DISABLING.finditer(text) if not re.search(r"\bjit\s*(?:=|\bTO\b)\s*off\b", m.group(2))]


def test_the_rule_sees_a_plan_node_turned_off_without_jit() -> None:
    assert disabling_without_jit_off('conn.execute("SET enable_seqscan = off")') == ["SET enable_seqscan = off"]
    assert disabling_without_jit_off("c.execute('SET LOCAL enable_sort TO OFF')") == ["SET LOCAL enable_sort TO OFF"]
    assert disabling_without_jit_off('"enable_nestloop = off",') == ["enable_nestloop = off"]
    assert disabling_without_jit_off('conn.execute("SET enable_seqscan = off; SET jit = off")') == []
    assert disabling_without_jit_off('"SET LOCAL enable_hashjoin = off; SET LOCAL jit = off"') == []
    assert disabling_without_jit_off('conn.execute("SET enable_seqscan = on")') == []


def test_a_test_that_turns_a_plan_node_off_turns_jit_off_in_the_same_statement() -> None:
    found = {
        path.name: bad
        for path in sorted(TESTS.glob("*.py"))
        if path.name != Path(__file__).name and (bad := disabling_without_jit_off(path.read_text(encoding="utf-8")))
    }
    assert found == {}, "add '; SET jit = off' (SET LOCAL jit = off) to these statements: " + repr(found)
