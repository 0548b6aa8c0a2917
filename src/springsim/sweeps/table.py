"""results.csv: one row per run, appended as runs finish and sorted by run number at the end.

While a sweep runs, each finished run's row is appended to OUT/results.csv at once (one write
of a whole line), so a sweep that is killed keeps every row it finished. When the sweep ends the
file is rewritten whole (atomically) in run order, so its content does not depend on the order
in which workers happened to finish. A sweep started again in the same folder reads the rows
back, keyed by ``run_id``, and runs only what is missing (resume).

Numbers are written as Python's ``repr`` (the shortest text that reads back to the same float),
so equal results give byte-identical files.
"""
import csv
import io
import os

from ..errors import require
from ..safe_files import atomic_output
from ..scenefile import parse_value
from .run import RESULTS, TIMINGS

FILE_NAME = "results.csv"
DONE = ("ok", "diverged")   # statuses a resumed sweep does not run again (errors are retried)
TEXT = ("run_id", "status", "message", "npz")   # columns read back as text, never as numbers


def columns(varied_keys, seeds: bool, save: bool) -> list[str]:
    """run number, run_id, a column per varied key (and the seed), status, message, results,
    wall_seconds, and the NPZ's path under OUT when runs are saved."""
    return (["run", "run_id", *varied_keys] + (["seed"] if seeds else [])
            + ["status", "message", *RESULTS, *TIMINGS] + (["npz"] if save else []))


def row_of(spec, outcome: dict, npz: str | None) -> dict:
    """The table row of ``spec`` and the dict its run returned, in column order (results a run
    did not reach are None)."""
    row = {"run": spec.index, "run_id": spec.run_id, **dict(spec.settings)}
    if spec.seed is not None:
        row["seed"] = spec.seed
    for column in ("status", "message", *RESULTS, *TIMINGS):
        row[column] = outcome.get(column)
    if spec.save:
        row["npz"] = npz or ""
    return row


def format_cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        from ..scenefile import toml_value
        return toml_value(value)
    return str(value)


def parse_row(row: dict) -> dict:
    """A row read back from the file, with numbers as numbers."""
    return {column: text if column in TEXT else parse_cell(text) for column, text in row.items()}


def parse_cell(text: str):
    """A cell read back: '' is None, numbers are numbers, anything else the text."""
    if text == "":
        return None
    value = parse_value(text)
    return value if isinstance(value, (bool, int, float, list)) else text


class ResultsTable:
    """OUT/results.csv of one sweep (module doc)."""

    def __init__(self, folder: str, header: list[str]):
        self.path = os.path.join(folder, FILE_NAME)
        self.header = header

    def read(self) -> dict:
        """run_id -> row (cells as text) of the rows already in the file; a last line cut short
        by a killed sweep is ignored. A file of another sweep (other columns) is refused."""
        if not os.path.exists(self.path):
            return {}
        with open(self.path, newline="", encoding="utf-8") as file:
            reader = csv.reader(file)
            header = next(reader, None)
            if header is None:
                return {}
            require(header == self.header, "--out", os.path.dirname(self.path),
                    f"holds a {FILE_NAME} of another sweep (columns {', '.join(header)}); give "
                    "another --out, or the same --vary, --seeds and --save to resume it")
            rows = [dict(zip(header, cells)) for cells in reader if len(cells) == len(header)]
        return {row["run_id"]: row for row in rows}

    def write(self, rows) -> None:
        """The whole file, rows in run order, written atomically."""
        rows = sorted(rows, key=lambda row: int(row["run"]))
        with atomic_output(self.path) as file:
            file.write(self._text(rows, header=True).encode())

    def append(self, row: dict) -> None:
        """One row at the end of the file, in one write (the header first if the file is new)."""
        new = not os.path.exists(self.path) or os.path.getsize(self.path) == 0
        text = self._text([row], header=new).encode()
        descriptor = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        try:
            os.write(descriptor, text)
        finally:
            os.close(descriptor)

    def _text(self, rows, header: bool) -> str:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        if header:
            writer.writerow(self.header)
        for row in rows:
            writer.writerow([format_cell(row.get(column)) for column in self.header])
        return buffer.getvalue()
