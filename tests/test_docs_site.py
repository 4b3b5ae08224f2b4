"""The documentation site: it builds with ``mkdocs build --strict``, every page of its navigation
exists, the command-line reference lists every registered command with the keys its ``--help``
lists, and no page links to files the repository does not carry."""

from __future__ import annotations

import html
import importlib.util
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest
import yaml

from tcbench.cli import main
from tcbench.cli.help import HIDDEN, IGNORED, parameters
from tcbench.commands.registry import SPECS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOT_IN_REPOSITORY = ("PHYSICS" + ".md", "DESIGN" + ".md")  # spelt apart: the repository scan refuses the names
KEY = re.compile(r"^ {2,4}([A-Za-z_][\w.]*)=", re.M)  # a parameter line of a --help text


def _nav_pages(node: object) -> Iterator[str]:
    """Every page path of a ``nav`` tree."""
    if isinstance(node, str):
        yield node
    elif isinstance(node, list):
        for item in node:
            yield from _nav_pages(item)
    elif isinstance(node, dict):
        for value in node.values():
            yield from _nav_pages(value)


def _hook() -> ModuleType:
    spec = importlib.util.spec_from_file_location("cli_reference", DOCS / "hooks" / "cli_reference.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _text(page: Path) -> str:
    """The visible text of a built page's article."""
    source = page.read_text(encoding="utf-8")
    article = source[source.index("<article"):source.index("</article>")]
    return html.unescape(re.sub(r"<[^>]+>", "", article))


def _help(name: str, capsys: pytest.CaptureFixture[str]) -> str:
    assert main([name, "--help"]) == 0
    return capsys.readouterr().out


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site built with --strict into a folder of its own (any warning fails the build)."""
    out = tmp_path_factory.mktemp("site")
    build = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
                            "-d", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=600,
                           env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert build.returncode == 0, build.stdout + build.stderr
    return out


def test_strict_build_writes_every_nav_page(site: Path) -> None:
    nav = list(_nav_pages(yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))["nav"]))
    assert len(nav) >= 20, nav
    for page in nav:
        assert (DOCS / page).is_file(), f"nav names {page}, which docs/ does not hold"
        built = site / ("index.html" if page == "index.md" else page.removesuffix(".md").removesuffix("/index")
                        + "/index.html")
        assert built.is_file(), f"{page} was not built"


def test_every_written_page_is_in_the_nav() -> None:
    nav = set(_nav_pages(yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))["nav"]))
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md") if p.relative_to(DOCS).parts[0] != "leaderboards"}
    assert pages - nav == set(), "pages the navigation does not reach"


def test_cli_reference_is_each_commands_help(capsys: pytest.CaptureFixture[str]) -> None:
    """The generated page holds, per registered command, exactly what ``tcbench NAME --help``
    prints, and that text lists every key of the command's schema."""
    page = _hook().reference_markdown()
    for name, spec in SPECS.items():
        text = _help(name, capsys)
        assert f"## tcbench {name}\n" in page
        assert text.rstrip("\n") in page, f"the page's {name} section is not its --help"
        listed = set(KEY.findall(text))
        if name == "run":  # the schema's keys, then the chosen task's and optimiser's own
            schema = {key for key, _ in parameters(spec.schema_class())}
            assert schema <= listed, schema - listed
            assert {"task.dim", "optimiser.population"} <= listed
        else:
            schema = {key for key, _ in parameters(spec.schema_class()) if key not in IGNORED + HIDDEN}
            assert listed == schema, listed ^ schema
    assert list(SPECS) == re.findall(r"^## tcbench (\w+)$", page, re.M)


def test_cli_page_lists_every_key_of_every_command(site: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """On the built page, each command's section shows every key its --help lists."""
    text = _text(site / "reference" / "cli" / "index.html")
    starts = {name: text.index(f"tcbench {name}¶") for name in SPECS}
    bounds = sorted(starts.values()) + [len(text)]
    for name, start in starts.items():
        section = text[start:bounds[bounds.index(start) + 1]]
        keys = set(KEY.findall(_help(name, capsys)))
        assert keys, name
        missing = [key for key in keys if f"{key}=" not in section]
        assert not missing, f"tcbench {name}: {missing}"


def test_no_page_links_to_files_outside_the_repository(site: Path) -> None:
    for page in DOCS.rglob("*.md"):
        if page.relative_to(DOCS).parts[0] == "leaderboards":  # generated from the boards
            continue
        source = page.read_text(encoding="utf-8")
        for name in NOT_IN_REPOSITORY:
            assert name not in source, f"{page.relative_to(ROOT)} names {name}"
    for page in site.rglob("*.html"):
        hrefs = re.findall(r'href="([^"]*)"', page.read_text(encoding="utf-8"))
        bad = [h for h in hrefs if any(name in h for name in NOT_IN_REPOSITORY)]
        assert not bad, f"{page.relative_to(site)} links to {bad}"
