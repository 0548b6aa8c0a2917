"""Every example of the README and of the tutorials runs: each page's fenced bash and python
blocks, top to bottom, in an empty folder per page. The helpers here are also the other docs
tests' (test_docs.py, test_docs_serve.py).

Conventions (the README and every page of docs/ follow them):

- every fenced block names its language: ``bash`` and ``python`` blocks are examples and run,
  top to bottom, in one empty folder per page; ``text`` is output shown, not run; ``toml`` is a
  scene file, parsed (and written to a file when ``<!-- file: NAME -->`` stands just before it,
  for the blocks after it to use); a ``python`` block after ``<!-- file: NAME -->`` is a script
  shown whole for another program to run (Blender), written to that file and not run itself;
- a ``text`` block whose first line is ``$ COMMAND`` is a transcript: the command runs and must
  print the rest of the block (line breaks aside, so a long line may be wrapped);
- ``<!-- no-run: REASON -->`` just before a block leaves it out (long-running or interactive
  commands), visibly, with the reason.
"""
import os
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
DIRECTIVE = re.compile(r"^<!--\s*(no-run|file):\s*(.*?)\s*-->$")
RUNNABLE = {"bash": "bash", "python": "python"}
KNOWN = {"bash", "python", "text", "toml"}


@dataclass
class Block:
    page: str
    line: int
    language: str
    code: str
    no_run: str | None = None    # the reason, where the block must not run
    file: str | None = None      # the file a toml block is written to
    printed: str | None = None   # what the block printed on stdout, once it ran

    def label(self) -> str:
        first = self.code.strip().splitlines()[0] if self.code.strip() else ""
        return f"{self.page}:{self.line} ({self.language}: {first[:60]})"


def blocks(path: Path) -> list[Block]:
    """Every fenced block of the page, in order, with the directive just before it."""
    lines = path.read_text(encoding="utf-8").splitlines()
    found, previous, i = [], "", 0
    page = str(path.relative_to(ROOT))
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if not opening:
            if lines[i].strip():
                previous = lines[i].strip()
            i += 1
            continue
        indent, language, start = opening.group(1), opening.group(2), i + 1
        i += 1
        body = []
        while i < len(lines) and not re.match(rf"^{indent}```\s*$", lines[i]):
            body.append(lines[i])
            i += 1
        i += 1
        directive = DIRECTIVE.match(previous)
        block = Block(page, start, language, textwrap.dedent("\n".join(body)) + "\n")
        if directive and directive.group(1) == "no-run":
            block.no_run = directive.group(2)
        elif directive:
            block.file = directive.group(2)
        found.append(block)
        previous = ""
    return found


def tool_folder(folder: Path) -> Path:
    """A folder with ``springsim`` and ``python`` that run this interpreter on this checkout."""
    bin_dir = folder / ".bin"
    bin_dir.mkdir()
    for name, command in (("springsim", f'"{sys.executable}" -m springsim'),
                          ("python", f'"{sys.executable}"')):
        script = bin_dir / name
        script.write_text(f'#!/bin/sh\nexec {command} "$@"\n')
        script.chmod(0o755)
    return bin_dir


def environment(folder: Path) -> dict:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(tool_folder(folder)), env.get("PATH", "")])
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT / "src"),
                                                      env.get("PYTHONPATH")]))
    env.update(MPLBACKEND="Agg", NO_MKDOCS_2_WARNING="1")
    return env


def run_page(path: Path, folder: Path, timeout: float = 600) -> list[Block]:
    """Run the page's examples in order in ``folder``; raise AssertionError naming the first
    block that fails, with its output. Returns the blocks that ran."""
    import tomllib

    env = environment(folder)
    ran = []
    for number, block in enumerate(blocks(path)):
        assert block.language in KNOWN, (
            f"{block.label()}: a fenced block must say its language, one of {sorted(KNOWN)}")
        if block.language == "toml":
            tomllib.loads(block.code)   # a scene file or a piece of one: valid TOML at least
        elif block.language == "python" and block.file:
            compile(block.code, block.file, "exec")     # a script for another program: valid
        if block.file or block.language == "toml":
            if block.file:
                (folder / block.file).write_text(block.code, encoding="utf-8")
            continue
        transcript = block.language == "text" and block.code.startswith("$ ")
        if block.no_run is not None or not (block.language in RUNNABLE or transcript):
            continue
        if transcript:
            command_line, expected = block.code.split("\n", 1)
            done = subprocess.run(["bash", "-c", command_line[2:]], cwd=folder, env=env,
                                  capture_output=True, text=True, timeout=timeout)
            printed = " ".join((done.stdout + done.stderr).split())
            assert printed == " ".join(expected.split()), (
                f"{block.label()}: the command now prints\n{done.stdout}{done.stderr}")
            ran.append(block)
            continue
        if block.language == "bash":
            command = ["bash", "-euo", "pipefail", "-c", block.code]
        else:
            script = folder / f".block_{number}.py"
            script.write_text(block.code, encoding="utf-8")
            command = [sys.executable, str(script)]
        done = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True,
                              timeout=timeout)
        assert done.returncode == 0, (
            f"{block.label()} failed with exit code {done.returncode}\n"
            f"--- stdout ---\n{done.stdout[-3000:]}\n--- stderr ---\n{done.stderr[-3000:]}")
        block.printed = done.stdout
        ran.append(block)
    return ran


PAGES = ["README.md", "docs/getting-started.md", "docs/guide/command-line.md",
         *sorted(str(path.relative_to(ROOT))
                 for path in (ROOT / "docs" / "tutorials").glob("*.md"))]


NEEDS_BLENDER = {"docs/tutorials/blender.md"}    # its scripts run in bpy, Blender as a module


# the slow tier: each page's commands run as a user types them (49 processes, minutes)
@pytest.mark.slow
@pytest.mark.parametrize("page", [pytest.param(page, marks=pytest.mark.external)
                                  if page in NEEDS_BLENDER else page for page in PAGES])
def test_page_examples_run(page, tmp_path):
    ran = run_page(ROOT / page, tmp_path)
    assert ran, f"{page} has no runnable example"
    if page == "README.md":
        check_recording_is_documented(tmp_path / "jelly-balls.npz")
        check_sweep_rows_differ(tmp_path / "sweep" / "results.csv")
    if page == "docs/getting-started.md":
        check_runs_differ(tmp_path / "soft_bowl.npz", tmp_path / "sticky.npz")
    if page == "docs/tutorials/cloth-and-balls.md":
        check_runs_differ(tmp_path / "cloth-drape.npz", tmp_path / "thick.npz")
    if page == "docs/tutorials/sweeps.md":
        check_sweep_rows_differ(tmp_path / "sweep-ks" / "results.csv")
        python = [block for block in ran if block.language == "python"]
        check_printed_rows_differ(python[0].printed)


def check_runs_differ(*recordings: Path, by: float = 0.01):
    """Runs that an example varies show the effect they are about: their last frames' centres
    differ by more than ``by`` m (a run that ends before the body reaches what the varied key
    acts on gives the same frames)."""
    centres = []
    for path in recordings:
        with np.load(path) as arrays:
            centres.append(arrays["positions"][-1].mean(axis=0))
    for a in range(len(centres)):
        for b in range(a):
            assert np.abs(centres[a] - centres[b]).max() > by, (recordings[a], recordings[b])


def check_sweep_rows_differ(table: Path, by: float = 1e-3):
    """Every two rows of a sweep's results differ, by a relative ``by`` at least in one result
    (the timings aside)."""
    import csv

    from springsim.sweeps.run import RESULTS

    with table.open() as file:
        rows = [[float(row[column]) for column in RESULTS] for row in csv.DictReader(file)]
    rows = np.array(rows)
    for a in range(len(rows)):
        for b in range(a):
            scale = np.abs(rows[a]) + np.abs(rows[b]) + 1e-12
            assert (np.abs(rows[a] - rows[b]) / scale).max() > by, (a, b, rows[a], rows[b])


def check_printed_rows_differ(printed: str):
    """An example that prints a row per varied run shows the effect: the rows' last numbers
    (the result it prints) all differ."""
    results = [line.split()[-1] for line in printed.strip().splitlines()]
    assert len(results) > 1 and len(set(results)) == len(results), printed


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
