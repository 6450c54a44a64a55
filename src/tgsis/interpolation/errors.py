"""Errors of the morphological interpolation set-up.

:class:`InterpolationSetupError` derives from
:class:`tgsis.errors.InvalidInputError` (SQLSTATE ``TG100``), so callers that
catch invalid input catch it too. It says which path, patch or mesh is wrong;
when several things are wrong at once, :attr:`InterpolationSetupError.problems`
lists each of them and the message shows them one per line.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from tgsis.errors import InvalidInputError

__all__ = ["InterpolationSetupError"]


class InterpolationSetupError(InvalidInputError):
    """The user's interpolation set-up is wrong: a path that is not a path, a patch that is not a disk, ...

    Parameters
    ----------
    message : str
        What is wrong, naming the path or patch at fault. Ignored when
        ``problems`` has more than one entry: the message then counts them and
        lists each on its own line.
    problems : sequence of str, optional
        Every problem found (default: just ``message``).
    **kwargs
        ``detail`` and ``hint``, as for :class:`tgsis.errors.Error`.

    Attributes
    ----------
    problems : tuple of str
        One line per problem, each naming its path or patch.
    """

    def __init__(self, message: str, *, problems: Sequence[str] | None = None, **kwargs: Any) -> None:
        found = tuple(problems) if problems else (message,)
        if len(found) > 1:
            message = f"{message}: {len(found)} problems\n" + "\n".join(f"- {p}" for p in found)
        super().__init__(message, **kwargs)
        self.problems = found

    @classmethod
    def collect(cls, what: str, problems: Sequence[str], **kwargs: Any) -> InterpolationSetupError:
        """One error for all ``problems``: the single problem itself, or ``what`` followed by the list.

        Parameters
        ----------
        what : str
            Heading when there are several problems (e.g. ``"source partition"``).
        problems : sequence of str
            At least one problem.
        """
        if len(problems) == 1:
            return cls(problems[0], **kwargs)
        return cls(what, problems=problems, **kwargs)
