"""A chart of one result of a sweep against one varied key: a line per combination of the other
varied keys, a point per seed, the line through the seeds' mean. Runs that did not finish (status
diverged or error) are left out; a value of the key where every run failed shows as a gap."""
import os

import numpy as np

from ..errors import require
from .run import RESULTS


def parse_plot(text: str, keys: list[str], out: str | None) -> tuple[str, str, str]:
    """``KEY:RESULT`` or ``KEY:RESULT:PATH`` checked against the varied keys, the result columns
    and the file system: (key, result, path of the PNG; by default OUT/RESULT-vs-KEY.png)."""
    key, _, rest = str(text).partition(":")
    result, _, path = rest.partition(":")
    require(key in keys and result in RESULTS, "--plot", text,
            "must be KEY:RESULT or KEY:RESULT:PATH with KEY one of "
            + ", ".join(keys or ["(nothing varied)"]) + " and RESULT one of " + ", ".join(RESULTS))
    require(path or out is not None, "--plot", text, "needs --out, or a PATH for the chart")
    path = path or os.path.join(out, f"{result}-vs-{key}.png")
    require(path.lower().endswith(".png"), "--plot", text, "the chart's PATH must end in .png")
    folder = os.path.dirname(os.path.abspath(path))
    require(os.path.isdir(folder) or folder == os.path.abspath(out or ""), "--plot", text,
            f"the folder {folder} does not exist")
    return key, result, path


def plot_sweep(rows, key: str, result: str, path) -> None:
    """Write the chart (PNG) of ``result`` against ``key`` over the table ``rows``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..safe_files import atomic_output

    others = [column for column in varied_columns(rows) if column not in (key, "seed")]
    values = list(dict.fromkeys(row[key] for row in rows))
    numeric = all(isinstance(value, (int, float)) and not isinstance(value, bool)
                  for value in values)
    position = {value: (value if numeric else k) for k, value in enumerate(values)}
    figure = Figure(figsize=(7, 4.5), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    groups = {}
    for row in rows:
        groups.setdefault(tuple(row[column] for column in others), []).append(row)
    for group, members in groups.items():
        label = ", ".join(f"{column} = {value}" for column, value in zip(others, group))
        xs, means = [], []
        for value in values:
            finished = [row[result] for row in members
                        if row[key] == value and row["status"] == "ok"]
            xs.append(position[value])
            means.append(np.mean(finished) if finished else np.nan)
            axes.plot([position[value]] * len(finished), finished, ".", color="0.6")
        axes.plot(xs, means, "o-", label=label or None)
    if not numeric:
        axes.set_xticks(range(len(values)), [str(value) for value in values])
    axes.set_xlabel(key)
    axes.set_ylabel(result)
    axes.set_title(f"{result} against {key} ({len(rows)} runs)", fontsize="medium")
    axes.grid(alpha=0.3)
    if others:
        axes.legend(fontsize="small")
    with atomic_output(path) as file:
        figure.savefig(file, format="png")


def varied_columns(rows) -> list[str]:
    """The columns between run_id and status: the varied keys (and the seed)."""
    names = list(rows[0]) if rows else []
    if "run_id" not in names or "status" not in names:
        return []
    return names[names.index("run_id") + 1:names.index("status")]
