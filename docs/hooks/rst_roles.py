"""A Griffe extension for the API pages: the package's docstrings are reStructuredText-ish
(``code``, :class:`Name`, ``text::`` before a literal block, a section title underlined with
dashes); the site renders Markdown, so each role becomes inline code naming its target (``~``
keeps the last component, as Sphinx does), a paragraph's closing ``::`` one colon, and an
underlined title bold text rather than a heading of the page."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|mod|data|meth|attr|exc|obj|const):`(~?)([^`]+)`")
LITERAL = re.compile(r"(\S)::$", re.M)
UNDERLINED = re.compile(r"^(\S[^\n]*)\n-{3,}[ \t]*$", re.M)


def _target(match: re.Match[str]) -> str:
    short, target = match.group(1), match.group(2).lstrip(".")
    return f"`{target.rsplit('.', 1)[-1] if short else target}`"


def markdown(text: str) -> str:
    """``text`` with its reST roles as inline code, its literal-block markers as one colon and its
    underlined titles in bold."""
    return UNDERLINED.sub(r"**\1**", LITERAL.sub(r"\1:", ROLE.sub(_target, text)))


class RestRoles(griffe.Extension):
    """Rewrite every docstring with :func:`markdown` once the object tree is built."""

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
