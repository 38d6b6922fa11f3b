"""Run one benchmark command on two or more source trees of wrinkle in turns, round after
round, each run in its own process with PYTHONPATH set to the tree, and print the lines of
its output that match a pattern.

This machine is shared and its speed drifts: some minutes both cores run at full speed, in
others one of them is mostly taken (then a parallel loop runs no faster on two threads than
on one, and every multi-threaded part of a solve, PARDISO included, is several times
slower). Before each run a probe times a parallel Numba loop on one and on two threads; a
ratio well below 2 flags a run that should not be compared. Medians and ratios of such
runs are what the performance pages quote.

    git worktree add ../before 8d92005
    python benchmarks/in_turns.py --trees ../before/src src --rounds 3 --match "new " -- \\
        benchmarks/rectangle_speed.py --sizes 320 --settings new
    python benchmarks/in_turns.py --trees ../before/src src --match "airbag" -- \\
        benchmarks/scale.py --problems airbag_nested --sizes 704 --max-elements 2e6
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time

PROBE = """
import time
import numba
import numpy as np

@numba.njit(parallel=True)
def load(a):
    s = 0.0
    for i in numba.prange(a.size):
        s += np.sin(a[i])
    return s

a = np.random.default_rng(0).random(10**7)
best = []
for threads in (1, 2):
    numba.set_num_threads(threads)
    load(a)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        load(a)
        times.append(time.perf_counter() - start)
    best.append(min(times))
one, two = best
print(f"{1e3 * one:.0f} ms on 1 thread, {1e3 * two:.0f} ms on 2: ratio {one / two:.2f}")
"""


def probe() -> str:
    """The parallel probe's line (module docstring), or why it could not run."""
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True)
    return done.stdout.strip() or f"probe failed: {done.stderr.strip()[-200:]}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trees", nargs="+", required=True, help="src folders, in turn order")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--match", default="", help="print the output lines matching this")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- script and its arguments")
    args = parser.parse_args()
    command = [part for part in args.command if part != "--"]
    if not command:
        parser.error("give the benchmark command after --")
    pattern = re.compile(args.match)
    for round_ in range(1, args.rounds + 1):
        for tree in args.trees:
            environment = {**os.environ, "PYTHONPATH": os.path.abspath(tree)}
            checked = probe()
            start = time.perf_counter()
            done = subprocess.run(
                [sys.executable, *command], capture_output=True, text=True, env=environment
            )
            seconds = time.perf_counter() - start
            print(f"round {round_}, {tree} ({seconds:.0f} s; probe: {checked})", flush=True)
            # each matching line once (scripts that print their table as it grows repeat it)
            lines = list(
                dict.fromkeys(line for line in done.stdout.splitlines() if pattern.search(line))
            )
            for line in lines or [f"exit status {done.returncode}: {done.stderr.strip()[-300:]}"]:
                print(f"    {line}", flush=True)


if __name__ == "__main__":
    main()
