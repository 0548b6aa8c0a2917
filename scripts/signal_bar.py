"""The issue's bar for Ctrl-C and SIGTERM: 50 SIGINT and 50 SIGTERM sent at random moments to
`springsim run`, and 10 of each to every other long command (render, sweep, export, stability,
convergence); every one must end with the one line "interrupted" or "terminated", exit 130 or
143, no traceback and no half-written file (tests/signal_trials.py says what is checked).

    .venv/bin/python scripts/signal_bar.py [--run 50] [--others 10] [--seed 1]

Prints a line per command and signal (trials, failures) and each failure; exits 1 if any.
It takes about half an hour (a trial is a few seconds); tests/test_signals.py runs a few.
"""
import argparse
import signal
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import signal_trials


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=int, default=50, help="trials of each signal on run")
    parser.add_argument("--others", type=int, default=10,
                        help="trials of each signal on every other command")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    failures = 0
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        signal_trials.prepare(folder)
        for command in signal_trials.LONG_COMMANDS:
            for signum in (signal.SIGINT, signal.SIGTERM):
                count = args.run if command == "run" else args.others
                bad = []
                for delay in signal_trials.random_delays(command, count, args.seed + signum):
                    result = signal_trials.trial(command, signum, folder, delay)
                    if result.problems():
                        bad.append(result)
                    for left in result.left:   # each trial starts from the same folder
                        path = Path(left)
                        if path.is_file():
                            path.unlink()
                    for left in sorted(result.left, reverse=True):
                        if Path(left).is_dir():
                            Path(left).rmdir()
                print(f"{command:<12} {signal.Signals(signum).name:<8} {count:>3} trials, "
                      f"{len(bad)} failed", flush=True)
                for result in bad:
                    print(f"    at {result.delay:.2f} s: {'; '.join(result.problems())}",
                          flush=True)
                failures += len(bad)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
