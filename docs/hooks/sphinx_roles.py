"""Griffe extension: render the Sphinx roles some docstrings carry (``:func:`x```, ``:data:`x```,
...).

The docs are Markdown with Google-style docstrings; a Sphinx role would show as raw text. Each role
becomes an inline code span of its target (``~`` keeps the last name only, as in Sphinx), and a
reStructuredText double-backtick literal becomes a Markdown code span; ``text::`` before a literal
block becomes ``text:``.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|data|class|mod|meth|attr|exc|obj|const)(?:`|:`)(~?)([^`]+)`")
DOUBLE = re.compile(r"``([^`]+)``")
#: reStructuredText's "text::" that introduces an indented literal block (which Markdown shows as
#: code).
LITERAL_INTRO = re.compile(r"(?<=\S)::$", re.MULTILINE)


def markdown(text: str) -> str:
    """A docstring with its Sphinx roles and ``literals`` as Markdown code spans."""
    text = ROLE.sub(
        lambda m: f"`{m.group(2).rsplit('.', 1)[-1] if m.group(1) else m.group(2)}`", text
    )
    return LITERAL_INTRO.sub(":", DOUBLE.sub(r"`\1`", text))


class SphinxRoles(griffe.Extension):
    """Rewrites every loaded object's docstring once, before it is parsed."""

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
