"""Running a study's variants: in this process, in local processes, or on a Dask cluster.

Each variant is the base case with its values set (``design.variant_overrides``), run by
``Case.run`` into its own results folder, ``OUT/variants/NNNN``; its row of the study table
(``table.py``) holds its parameters, the quantities of its last step (the last row of its
history.csv: reactions, probe displacements, areas, energies, ...; and ``frequency_N`` where
the case asks for modes), its ``status`` ("converged", "not converged" or "error"), the
message of a failure, its wall seconds and its folder. A variant that fails is a row with its
error; the study goes on. A finished variant leaves ``variant.json`` in its folder, and a study
run again takes those rows up instead of solving them again.

Engines (``run_study``): with a scheduler address, the Dask cluster there
(``distributed.Client``); else a ``distributed.LocalCluster`` of ``workers`` processes where
Dask is installed (the ``study`` extra), or a pool of local processes where it is not; with
``workers = 1`` and no address, one variant after the other in this process. Every worker
limits BLAS, OpenMP, MKL (PARDISO) and Numba to one thread, so that the workers share the
cores instead of fighting over them.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import hashlib
import json
import logging
import multiprocessing
import os
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from wrinkle.studies.design import BOOKKEEPING, Study, StudyError, variant_overrides

__all__ = ["ENGINES", "THREAD_VARIABLES", "VariantTask", "dask_client", "run_study", "run_variant"]

# where the variants run (``run_study``): "auto" is Dask where installed or given a scheduler,
# else local processes, and this process for one worker
ENGINES = ("auto", "dask", "processes", "here")

# the thread counts of the numerical libraries, set to 1 in every worker
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMBA_NUM_THREADS",
)
VARIANT_FILE = "variant.json"
# The local cluster's workers, unlike Dask's defaults: glibc's own (dynamic) threshold for
# giving freed memory back to the system instead of Dask's MALLOC_TRIM_THRESHOLD_ = 65536,
# which made each airbag variant 35 % slower (its large NumPy arrays mapped and unmapped
# again at every allocation), and no statistical profiler (it feeds the dashboard, which is
# off; sampling the solver's stack every 10 ms cost 15 %). docs/studies.md, Cost.
MALLOC_TRIM = "MALLOC_TRIM_THRESHOLD_"
LOCAL_CLUSTER_CONFIG = {
    f"distributed.nanny.pre-spawn-environ.{MALLOC_TRIM}": None,
    "distributed.worker.profile.enabled": False,
}


@dataclass(frozen=True)
class VariantTask:
    """One variant to run: its number (from 1), the base case file, the read_case overrides
    that make it, its values {path: value}, its results folder, that folder's name in the
    study's folder (``folder_name``) and the fingerprint of its input (``fingerprint``)."""

    number: int
    case: str
    overrides: dict[str, Any]
    values: dict[str, float]
    folder: str
    name: str
    fingerprint: str = ""  # of the variant's input (``fingerprint``)


def fingerprint(case: Path, base: dict[str, Any], overrides: dict[str, Any]) -> str:
    """A SHA-256 of a variant's input: the base case file's bytes, the mesh files it names
    (``[mesh] file`` and ``levels``) and the variant's overrides. A study run again takes a
    finished variant up only if its input is the same."""
    digest = hashlib.sha256(case.read_bytes())
    mesh = base.get("mesh", {}) if isinstance(base.get("mesh"), dict) else {}
    files = [mesh.get("file")] + list(mesh.get("levels") or [])
    for name in files:
        if isinstance(name, str) and (case.parent / name).is_file():
            digest.update((case.parent / name).read_bytes())
    digest.update(json.dumps(overrides, sort_keys=True, default=str).encode())
    return digest.hexdigest()


def folder_name(number: int) -> str:
    """The results folder of variant ``number``, relative to the study's folder."""
    return os.path.join("variants", f"{number:04d}")


def _quantities(folder: Path) -> dict[str, float]:
    """The quantities of a results folder's last step: its history row's numbers but the
    bookkeeping columns, and ``frequency_N`` from the summary where it has modes."""
    from wrinkle.reader import open_results

    results = open_results(folder)
    quantities: dict[str, float] = {}
    for name, column in results.history.items():
        if name not in BOOKKEEPING and len(column):
            quantities[name] = float(column[-1])
    for index, value in enumerate(results.summary.get("frequencies") or []):
        quantities[f"frequency_{index + 1}"] = float(value)
    return quantities


@contextlib.contextmanager
def _one_thread() -> Iterator[None]:
    """BLAS, OpenMP and MKL limited to one thread (threadpoolctl, where installed) and Numba's
    threads to one, within the block."""
    limits: contextlib.AbstractContextManager[Any] = contextlib.nullcontext()
    with contextlib.suppress(ImportError):
        from threadpoolctl import threadpool_limits

        limits = threadpool_limits(1)
    with limits:
        with contextlib.suppress(ImportError, ValueError):
            import numba

            numba.set_num_threads(1)
        yield


def run_variant(task: VariantTask) -> dict[str, Any]:
    """Run one variant into its folder (``Case.run``, quietly, one thread) and return its row:
    "variant", its values, its quantities (``_quantities``; none for a failure), "status",
    "message", "seconds" and "folder". Never raises for the variant's own failure: a case the
    variant makes invalid is status "error", a solve that does not converge "not converged".
    Writes the row into the folder's variant.json."""
    from wrinkle.case import read_case
    from wrinkle.solvers import ConvergenceError

    start = time.perf_counter()
    for name in THREAD_VARIABLES:  # for the libraries this worker has not loaded yet
        os.environ.setdefault(name, "1")
    folder = Path(task.folder)
    status, message, quantities = "converged", "", {}
    with _one_thread():
        try:
            case = read_case(task.case, task.overrides)
            case.run(folder)
            quantities = _quantities(folder)
        except ConvergenceError as error:
            status, message = "not converged", str(error)
        except (ValueError, RuntimeError, OSError, ArithmeticError) as error:
            status, message = "error", str(error) or type(error).__name__
        except Exception as error:  # a bug: recorded with its place, the study goes on
            status = "error"
            message = f"{type(error).__name__}: {error} ({traceback.format_exc(limit=-1)!r})"
    row = {
        "variant": task.number,
        **task.values,
        **quantities,
        "status": status,
        "message": message.replace("\n", " "),
        "seconds": time.perf_counter() - start,
        "folder": task.name,
    }
    folder.mkdir(parents=True, exist_ok=True)
    record = {**row, "fingerprint": task.fingerprint}
    (folder / VARIANT_FILE).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    return row


def _done(task: VariantTask) -> dict[str, Any] | None:
    """The row of a variant finished (converged or not) by an earlier run of the study from
    the same input (the same ``fingerprint``), or None."""
    path = Path(task.folder) / VARIANT_FILE
    try:
        row = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    same = row.pop("fingerprint", None) == task.fingerprint and row.get("variant") == task.number
    return row if same else None


@contextlib.contextmanager
def _worker_environment() -> Iterator[None]:
    """While worker processes start (they inherit it): the thread variables set to 1, and
    no MALLOC_TRIM_THRESHOLD_ (``LOCAL_CLUSTER_CONFIG``; a Dask cluster started before in
    this process leaves its value in os.environ)."""
    saved = {name: os.environ.get(name) for name in (*THREAD_VARIABLES, MALLOC_TRIM)}
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    os.environ.pop(MALLOC_TRIM, None)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def dask_client(scheduler: str | None, workers: int, required: bool):
    """A ``distributed.Client`` of the cluster at ``scheduler``, or of a LocalCluster of
    ``workers`` single-threaded processes; None without Dask unless ``required``.
    StudyError for an address that does not answer or Dask missing where required."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        if required:
            raise StudyError(
                f"--scheduler {scheduler}: Dask is not installed; pip install 'wrinkle[study]'"
            ) from None
        return None
    if scheduler is not None:
        try:
            return Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as error:
            raise StudyError(
                f"--scheduler {scheduler}: no Dask scheduler answers ({error})"
            ) from None
    for name in ("distributed", "tornado"):  # the cluster's chatter stays off the terminal
        logging.getLogger(name).setLevel(logging.ERROR)
    import dask

    with _worker_environment(), dask.config.set(LOCAL_CLUSTER_CONFIG):
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    return Client(cluster)


def run_study(
    study: Study,
    out: str | os.PathLike,
    scheduler: str | None = None,
    workers: int | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
    engine: str = "auto",
) -> list[dict[str, Any]]:
    """Run every variant of ``study`` into ``out`` (the module docstring): the rows in
    variant order, each handed to ``on_row`` as it finishes (the rows of variants done by an
    earlier run first). workers: the local processes (default the machine's cores); engine:
    one of ENGINES. StudyError for an unknown engine, a scheduler that does not answer or
    Dask asked for and missing."""
    if engine not in ENGINES:
        raise StudyError(f"engine {engine!r}: one of {', '.join(ENGINES)}")
    out = Path(out).resolve()  # (a remote worker's working folder is not this one)
    out.mkdir(parents=True, exist_ok=True)
    workers = workers or os.cpu_count() or 1
    tasks = []
    for number, values in enumerate(study.variants, start=1):
        overrides = variant_overrides(study.base, values)
        tasks.append(
            VariantTask(
                number,
                str(study.case),
                overrides,
                values,
                str(out / folder_name(number)),
                folder_name(number),
                fingerprint(study.case, study.base, overrides),
            )
        )
    rows: dict[int, dict[str, Any]] = {}

    def finished(row: dict[str, Any]) -> None:
        rows[int(row["variant"])] = row
        if on_row is not None:
            on_row(row)

    pending = []
    for task in tasks:
        row = _done(task)
        if row is None:
            pending.append(task)
        else:
            finished(row)
    if engine == "auto":
        engine = "here" if scheduler is None and workers == 1 else "dask"
    if pending and engine == "here":
        for task in pending:
            finished(run_variant(task))
    elif pending:
        client = None
        if engine == "dask":
            client = dask_client(scheduler, workers, required=scheduler is not None)
        if client is not None:
            from distributed import as_completed

            try:
                futures = client.map(run_variant, pending, pure=False)
                for future in as_completed(futures):
                    finished(future.result())
            finally:
                cluster = getattr(client, "cluster", None)
                client.close()
                if scheduler is None and cluster is not None:
                    cluster.close()
        else:  # the workers start as tasks are submitted: the variables set meanwhile
            context = multiprocessing.get_context("spawn")
            with (
                _worker_environment(),
                concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool,
            ):
                for future in concurrent.futures.as_completed(
                    [pool.submit(run_variant, task) for task in pending]
                ):
                    finished(future.result())
    return [rows[number] for number in sorted(rows)]
