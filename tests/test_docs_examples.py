"""Every example of the README and of the documentation's guides runs: each page's fenced bash
and python blocks, top to bottom, in an empty folder (conventions in tests/docs_examples.py)."""
import re
from pathlib import Path

import numpy as np
import pytest

from docs_examples import ROOT, blocks, run_page

PAGES = ["README.md", "docs/getting-started.md",
         *sorted(str(path.relative_to(ROOT)) for path in (ROOT / "docs" / "tutorials").glob("*.md"))]


@pytest.mark.parametrize("page", PAGES)
def test_page_examples_run(page, tmp_path):
    ran = run_page(ROOT / page, tmp_path)
    assert ran, f"{page} has no runnable example"
    if page == "README.md":
        check_recording_is_documented(tmp_path / "jelly-balls.npz")


def check_recording_is_documented(recording: Path):
    """The README's run wrote a recording: every array in it is in the output-files page's
    table, and every array the table names is in it."""
    text = (ROOT / "docs" / "guide" / "output-files.md").read_text()
    table = text.split("## The NPZ recording", 1)[1].split("\n## ", 1)[0]
    documented = set(re.findall(r"^\| `(\w+)` \|", table, re.M))
    with np.load(recording) as arrays:
        assert set(arrays.files) == documented


def test_examples_follow_the_conventions():
    """Every page's fenced blocks say their language, and the blocks left out are few and say
    why (the test above runs all the others)."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    left_out = []
    for page in pages:
        if page.name == "architecture.md":    # owned and kept as its author writes it
            continue
        for block in blocks(page):
            assert block.language, f"{block.label()}: say the block's language"
            if block.no_run is not None:
                assert block.no_run, f"{block.label()}: a no-run block must say why"
                if str(page.relative_to(ROOT)) in PAGES:
                    left_out.append(block.label())
    assert len(left_out) <= 8, left_out
