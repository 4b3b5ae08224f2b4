"""MkDocs hook: the command-line reference, rendered at build time from the registry that every
``tcbench <command> --help`` is generated from (:data:`tcbench.commands.registry.SPECS` and
:func:`tcbench.cli.help.usage`), so the page cannot drift from the commands.

A page holding :data:`PLACEHOLDER` gets, in its place, ``tcbench --help`` and one section per
registered command: its summary and its ``--help`` text as the command prints it."""

from __future__ import annotations

import html
import re
from typing import Any

PLACEHOLDER = "<!-- tcbench-cli-reference -->"
_MARKDOWN_SPECIALS = re.compile(r"([\\`*_\[\]])")


def _prose(text: str) -> str:
    """Plain text as Markdown that renders it literally."""
    return _MARKDOWN_SPECIALS.sub(r"\\\1", html.escape(text, quote=False))


def command_markdown(name: str) -> str:
    """The section of command ``name``: a heading, its summary and its ``--help`` text."""
    from tcbench.cli.help import usage
    from tcbench.commands.registry import SPECS

    return "\n".join([f"## tcbench {name}", "", _prose(SPECS[name].summary), "", "```text", usage(name), "```", ""])


def reference_markdown() -> str:
    """``tcbench --help`` and every registered command's section, in the registry's order."""
    from tcbench.cli.main import USAGE
    from tcbench.commands.registry import SPECS

    index = ", ".join(f"[`{name}`](#tcbench-{name})" for name in SPECS)
    head = ["## tcbench", "", f"Commands: {index}.", "", "```text", USAGE.rstrip(), "```", ""]
    return "\n".join(head + [command_markdown(name) for name in SPECS])


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any, **kwargs: Any) -> str:
    """Replace the placeholder of the page that holds it."""
    if PLACEHOLDER not in markdown:
        return markdown
    return markdown.replace(PLACEHOLDER, reference_markdown())
