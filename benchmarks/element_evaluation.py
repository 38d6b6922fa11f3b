"""Where the time of one evaluation goes: forces, stiffness and energy of the inflated airbag.

On the quarter airbag of examples/airbag.toml at 224 x 224 squares (100,352 elements), at
displacement states a Newton solve from the flat sheet passes through (saved by
``--make-states``), the script times ``StepProblem.evaluate(u, stiffness=True)`` and
``stiffness=False`` (medians of ``--repeat`` runs), and then, in separate instrumented runs,
splits them into parts: each function of the list ``PARTS`` that exists in the code under test
is wrapped with a timer, and the time of a part excludes the parts called inside it (median
over the runs, milliseconds). It also counts the local Newton iterations of the wrinkled
elements (calls of the residual and the rows they evaluate) and the angle searches.

    python benchmarks/element_evaluation.py --make-states states.npz --iterations 5 20 40 60
    python benchmarks/element_evaluation.py --states states.npz --repeat 5
    python benchmarks/element_evaluation.py --states states.npz --compare OLD/src NEW/src \
        --rounds 3      # alternating subprocesses, side by side

``--make-states`` also counts the evaluations with and without stiffness per Newton iteration.
NumPy runs single-threaded (OMP_NUM_THREADS, OPENBLAS_NUM_THREADS, MKL_NUM_THREADS = 1).
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse
import functools
import importlib
import json
import logging
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

# (module, attribute path, label): the functions timed as parts, where they exist
PARTS = [
    ("wrinkle.system", "StepProblem.evaluate", "problem: residual, energy, matrix (rest)"),
    ("wrinkle.system", "DiscreteSystem.evaluate_elements", "element coordinates x[triangles]"),
    ("wrinkle.system", "DiscreteSystem.element_coordinates", "element coordinates x[triangles]"),
    ("wrinkle.element", "MembraneElements.evaluate", "element blocks: copies (rest)"),
    ("wrinkle.element", "deformation_gradient", "deformation gradient F"),
    ("wrinkle.element", "right_cauchy_green", "Cauchy-Green C"),
    ("wrinkle.compiled", "deformation_gradient", "F and C (Numba)"),
    ("wrinkle.wrinkling", "Wrinkling.response", "wrinkling: gather/scatter (rest)"),
    ("wrinkle.compiled", "svk_wrinkling", "wrinkling response (Numba, SVK)"),
    ("wrinkle.wrinkling", "Wrinkling.classify", "classification"),
    ("wrinkle.wrinkling", "Wrinkling._solve_conditions", "wrinkled: first guess (rest)"),
    ("wrinkle.wrinkling", "Wrinkling._newton", "wrinkled: local Newton (rest)"),
    ("wrinkle.wrinkling", "Wrinkling._residual_and_jacobian", "wrinkled: residual, Jacobian"),
    ("wrinkle.wrinkling", "Wrinkling._admissible", "wrinkled: admissibility (rest)"),
    ("wrinkle.wrinkling", "Wrinkling._residual", "wrinkled: residual (admissibility)"),
    ("wrinkle.wrinkling", "Wrinkling._angle_search", "wrinkled: angle search"),
    ("wrinkle.wrinkling", "Wrinkling._wrinkled_tangent", "wrinkled tangent"),
    ("wrinkle.compiled", "wrinkled_tangent", "wrinkled tangent"),
    ("wrinkle.materials.svk", "StVenantKirchhoff.response", "material response (SVK)"),
    ("wrinkle.materials.svk", "StVenantKirchhoff.energy", "material energy (SVK)"),
    ("wrinkle.materials.neo_hookean", "NeoHookean.response", "material response (neo-Hookean)"),
    ("wrinkle.materials.neo_hookean", "NeoHookean.energy", "material energy (neo-Hookean)"),
    ("wrinkle.element", "MembraneElements._forces_and_stiffness", "kernel sub-blocks (rest)"),
    ("wrinkle.element", "nodal_forces", "nodal forces"),
    ("wrinkle.compiled", "nodal_forces", "nodal forces"),
    ("wrinkle.compiled", "element_stiffness", "element stiffness (Numba)"),
    ("wrinkle.element", "element_stiffness", "element stiffness (NumPy)"),
    ("wrinkle.element", "strain_displacement", "B matrix (NumPy)"),
    ("wrinkle.system", "DiscreteSystem.subtract_pressure_stiffness", "pressure stiffness"),
    ("wrinkle.assembly", "SparsityPattern.add_to_data", "scatter into CSR data"),
    ("wrinkle.compiled", "assemble_stiffness", "element matrices formed and added (Numba)"),
    ("wrinkle.assembly", "SparsityPattern.assemble_vector", "assemble force vector"),
    ("wrinkle.system", "DiscreteSystem.follower_forces", "pressure forces"),
    ("wrinkle.system", "DiscreteSystem.pressure_work", "pressure work (energy)"),
]


def airbag_model(nx: int):
    from wrinkle.case import read_case

    return read_case(
        ROOT / "examples" / "airbag.toml", overrides={"mesh": {"rectangle": {"nx": nx, "ny": nx}}}
    ).model


# -- states -----------------------------------------------------------------------------
def make_states(path: Path, nx: int, iterations: list[int]) -> None:
    """Solve the airbag for max(iterations) Newton iterations; save u at the accepted point of
    each iteration in ``iterations`` and print the evaluations per iteration."""
    from wrinkle.solvers.base import ConvergenceError
    from wrinkle.system import StepProblem

    model = airbag_model(nx)
    current = {"iteration": -1, "u": None}
    saved, calls = {}, []

    class Marker(logging.Handler):
        def emit(self, record):
            message = record.getMessage()
            if " iteration " in message:
                current["iteration"] = int(message.split("iteration")[1].split(":")[0])
                if current["iteration"] in iterations:
                    saved[f"u{current['iteration']}"] = current["u"].copy()

    logger = logging.getLogger("wrinkle.solver")
    logger.setLevel(logging.INFO)
    logger.addHandler(Marker())
    evaluate = StepProblem.evaluate

    def counted(self, u, stiffness=True, **options):
        calls.append((current["iteration"], stiffness))
        evaluation = evaluate(self, u, stiffness=stiffness, **options)
        if stiffness:  # the solver logs the last point evaluated with stiffness
            current["u"] = np.array(u)
        return evaluation

    StepProblem.evaluate = counted
    try:
        model.solve(max_iterations=max(iterations), min_step=1.0)  # no cut-back
    except ConvergenceError:
        pass
    np.savez(path, **saved)
    calls = np.array(calls)
    newton = max(iterations)
    with_k, without_k = int(calls[:, 1].sum()), int((1 - calls[:, 1]).sum())
    # between two iterations' log lines, the last evaluation with stiffness is the accepted
    # point; the others are trial points that were rejected
    per_interval = np.bincount(calls[:, 0] + 1, weights=calls[:, 1]).astype(int)
    rejected = int(np.sum(np.maximum(per_interval - 1, 0)))
    print(f"saved {sorted(saved)} to {path}")
    print(
        f"{newton} Newton iterations: {with_k} evaluations with stiffness "
        f"({with_k / newton:.2f} per iteration; {rejected} of them, "
        f"{rejected / newton:.2f} per iteration, at rejected trial points), {without_k} "
        f"without ({without_k / newton:.2f} per iteration)"
    )


# -- timing -----------------------------------------------------------------------------
class PartTimer:
    """Wraps the functions of PARTS; seconds per label, exclusive of inner parts."""

    def __init__(self):
        self.seconds = defaultdict(float)
        self.counts = defaultdict(int)
        self._inner = []
        self._undo = []
        for module_name, attribute, label in PARTS:
            try:
                module = importlib.import_module(module_name)
            except ImportError:
                continue
            *owner_path, name = attribute.split(".")
            owner = module
            for part in owner_path:
                owner = getattr(owner, part, None)
            if owner is None or name not in vars(owner):
                continue
            original = vars(owner)[name]
            wrapped = self._wrap(original, label)
            if isinstance(original, staticmethod):
                wrapped = staticmethod(self._wrap(original.__func__, label))
            setattr(owner, name, wrapped)
            self._undo.append((owner, name, original))

    def _wrap(self, function, label):
        timer = self

        @functools.wraps(function)
        def timed(*args, **kwargs):
            if label == "wrinkled: residual, Jacobian":  # (self, e, phi or c, ...)
                timer.counts["residual rows"] += np.shape(args[2])[0]
                timer.counts["residual calls"] += 1
            elif label == "wrinkled: admissibility (rest)":
                timer.counts["admissibility rows"] += np.shape(args[2])[0]
            elif label == "wrinkled: angle search":
                timer.counts["angle search rows"] += np.shape(args[1][0])[0]
            start = time.perf_counter()
            timer._inner.append(0.0)
            try:
                return function(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - start
                timer.seconds[label] += elapsed - timer._inner.pop()
                if timer._inner:
                    timer._inner[-1] += elapsed

        return timed

    def restore(self):
        for owner, name, original in reversed(self._undo):
            setattr(owner, name, original)

    def reset(self):
        self.seconds.clear()
        self.counts.clear()


def measure(states: Path, nx: int, repeat: int) -> dict:
    """Timings of every state in ``states``: medians in ms, parts, counts, states."""
    from wrinkle.wrinkling import SLACK, WRINKLED

    model = airbag_model(nx)
    problem = model.discretise().at(1.0)
    data = np.load(states)
    out = {"elements": int(model.mesh.n_elements), "states": {}}
    for key in sorted(data.files, key=lambda k: int(k[1:])):
        u = data[key]
        problem.evaluate(u, stiffness=True)  # warm-up (compiles on the first call)
        row = {}
        result = model.discretise().evaluate_elements(u, stiffness=False)
        state = result.response.state
        row["wrinkled"] = float(np.mean(state == WRINKLED))
        row["slack"] = float(np.mean(state == SLACK))
        del result
        for stiffness in (True, False):
            times = []
            for _ in range(repeat):
                start = time.perf_counter()
                problem.evaluate(u, stiffness=stiffness)
                times.append(time.perf_counter() - start)
            row["K" if stiffness else "f"] = 1e3 * float(np.median(times))
        timer = PartTimer()
        try:
            for stiffness in (True, False):
                runs = []
                for _ in range(repeat):
                    timer.reset()
                    problem.evaluate(u, stiffness=stiffness)
                    runs.append((dict(timer.seconds), dict(timer.counts)))
                labels = {label for seconds, _ in runs for label in seconds}
                row["parts K" if stiffness else "parts f"] = {
                    label: 1e3 * float(np.median([s.get(label, 0.0) for s, _ in runs]))
                    for label in labels
                }
                row["counts K" if stiffness else "counts f"] = runs[-1][1]
        finally:
            timer.restore()
        out["states"][key] = row
    return out


def print_tables(results: list[tuple[str, dict]]) -> None:
    """One table per state: total and parts (ms) of each code side by side."""
    names = [name for name, _ in results]
    first = results[0][1]
    print(
        f"airbag, {first['elements']:,} elements; ms per evaluation, medians; parts exclude "
        "the parts inside them"
    )
    width = max(len(label) for *_, label in PARTS) + 2
    for key, row in first["states"].items():
        print(
            f"\nstate {key}: {100 * row['wrinkled']:.0f} % wrinkled, "
            f"{100 * row['slack']:.1f} % slack"
        )
        header = "".join(f"{name + ' K':>14}{name + ' f':>14}" for name in names)
        print(f"{'':<{width}}{header}")
        line = "".join(
            f"{r['states'][key]['K']:14.1f}{r['states'][key]['f']:14.1f}" for _, r in results
        )
        print(f"{'evaluate (uninstrumented)':<{width}}{line}")
        labels = [
            label
            for label in dict.fromkeys(label for *_, label in PARTS)
            if any(
                label in r["states"][key].get(f"parts {s}", {}) for _, r in results for s in "Kf"
            )
        ]
        for label in labels:
            line = "".join(
                "".join(
                    f"{r['states'][key][f'parts {s}'].get(label, float('nan')):14.1f}" for s in "Kf"
                )
                for _, r in results
            )
            print(f"{label:<{width}}{line}")
        total = "".join(
            "".join(f"{sum(r['states'][key][f'parts {s}'].values()):14.1f}" for s in "Kf")
            for _, r in results
        )
        print(f"{'sum of parts (instrumented)':<{width}}{total}")
        for name, r in results:
            counts = r["states"][key]["counts K"]
            calls = counts.get("residual calls", 0)
            rows = counts.get("residual rows", 0)
            wrinkled = max(1, row["wrinkled"] * first["elements"])
            print(
                f"  {name}: residual and Jacobian: {calls} calls, {rows:,} rows "
                f"({rows / wrinkled:.2f} per wrinkled element, admissibility checks "
                f"included where they use it); admissibility checks: "
                f"{counts.get('admissibility rows', 0) / wrinkled:.2f} per wrinkled element; "
                f"angle search on {counts.get('angle search rows', 0)} elements"
            )


def compare(sources: list[str], states: Path, nx: int, repeat: int, rounds: int) -> None:
    """Run ``measure`` under each source tree in turn, ``rounds`` times; medians per code."""
    runs = defaultdict(list)
    for round_ in range(rounds):
        for source in sources if round_ % 2 == 0 else sources[::-1]:
            environment = {**os.environ, "PYTHONPATH": source}
            output = subprocess.run(
                [
                    sys.executable,
                    __file__,
                    "--states",
                    str(states),
                    "--nx",
                    str(nx),
                    "--repeat",
                    str(repeat),
                    "--json",
                ],
                env=environment,
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            runs[source].append(json.loads(output.strip().splitlines()[-1]))
            print(f"round {round_ + 1}: {source} done", file=sys.stderr, flush=True)
    results = []
    for index, source in enumerate(sources):
        merged = runs[source][0]
        for key, row in merged["states"].items():
            rows = [r["states"][key] for r in runs[source]]
            for s in "Kf":
                row[s] = float(np.median([r[s] for r in rows]))
                labels = {label for r in rows for label in r[f"parts {s}"]}
                row[f"parts {s}"] = {
                    label: float(np.median([r[f"parts {s}"].get(label, 0.0) for r in rows]))
                    for label in labels
                }
        results.append((f"[{index}]", merged))
        print(f"[{index}] = {source}")
    print(f"medians over {rounds} alternating processes of medians of {repeat} runs")
    print_tables(results)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=224, help="squares per side (2 nx^2 elements)")
    parser.add_argument("--states", type=Path, help="npz of displacement vectors u<iteration>")
    parser.add_argument("--make-states", type=Path, help="solve and save states to this npz")
    parser.add_argument("--iterations", type=int, nargs="+", default=[5, 20, 40, 60])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--compare", nargs="+", metavar="SRC", help="source trees to compare")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args(argv)
    if args.make_states:
        make_states(args.make_states, args.nx, args.iterations)
        return
    if args.states is None:
        parser.error("--states (or --make-states) is required")
    if args.compare:
        compare(args.compare, args.states, args.nx, args.repeat, args.rounds)
        return
    result = measure(args.states, args.nx, args.repeat)
    if args.json:
        print(json.dumps(result))
    else:
        import wrinkle

        print_tables([(Path(wrinkle.__file__).parents[1].name, result)])


if __name__ == "__main__":
    main()
