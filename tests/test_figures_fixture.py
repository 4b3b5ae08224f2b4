"""The test session's figure rule (tests/conftest.py): built everywhere, rendered where marked."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pytest
from PIL import Image


def _draw(path: Path) -> Image.Image:
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    ax.set_title("a title")
    fig.tight_layout()
    fig.savefig(path, dpi=50)
    plt.close(fig)
    return Image.open(path)


def test_an_unmarked_test_gets_a_one_pixel_png(tmp_path: Path) -> None:
    assert _draw(tmp_path / "f.png").size == (1, 1)


@pytest.mark.figures
def test_a_marked_test_gets_the_rendered_figure(tmp_path: Path) -> None:
    assert _draw(tmp_path / "f.png").size == (200, 150)


def test_other_formats_and_buffers_are_rendered_everywhere(tmp_path: Path) -> None:
    fig, ax = plt.subplots()
    ax.set_title("svg")
    fig.savefig(tmp_path / "f.svg")
    plt.close(fig)
    text = (tmp_path / "f.svg").read_text()
    assert text.count("<path") > 10  # the axes, ticks and the title's glyphs, drawn
