"""Parameter sweeps: many variants of one study, run in parallel on a Dask cluster.

``sweep(study, variants, outputs)`` runs one case per variant (a dict of study-file key paths
to values), each in its own results folder, and returns one row per case: the variant's
values, the chosen scalar outputs, the wall time and, for a case that failed, its error (the
other cases complete). Reduced bodies are shared between the cases through one cache folder:
a part is reduced once for all the cases whose reduction settings agree (a first wave reduces
each distinct set of parts, then every case runs and finds its bodies in the cache).

The engine is Dask distributed (``pip install "flexmbs[sweep]"``): pure Python, light enough
for a laptop or a 2-core CI runner (a ``LocalCluster`` starts in about a second), and the same
``Client`` connects to a real cluster (``dask-scheduler`` plus ``dask-worker`` on each machine,
or dask-jobqueue on a batch system). Without Dask, ``sweep(..., client=None)`` runs the cases one
after the other in this process. Ray would do as well; it is a larger dependency with its own
object store and dashboard that a sweep of independent cases does not need.
"""

from __future__ import annotations

import itertools
import math
import os
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np

Variant = Dict[str, Any]
Output = Callable[[Any], float]

__all__ = ["grid", "sweep", "peak_abs", "final", "summary_value", "SweepCase"]


def grid(**axes: Sequence[Any]) -> List[Variant]:
    """The Cartesian product of value lists, one dict per combination.

    Keys are study-file key paths; since they contain dots, pass them as a dict:
    ``grid(**{"parts.rod.section.diameter": [0.004, 0.006], "drivers.crank.speed": [100, 150]})``.
    The last key varies fastest.
    """
    keys = list(axes)
    for k in keys:
        if isinstance(axes[k], (str, bytes)) or not hasattr(axes[k], "__iter__"):
            raise TypeError(f"grid: the values of {k!r} must be a list, got {axes[k]!r}")
    return [dict(zip(keys, combo)) for combo in itertools.product(*(list(axes[k]) for k in keys))]


def peak_abs(sensor: str, column: Optional[Union[int, str]] = None) -> Output:
    """An output: the largest absolute value of a sensor's column (all columns if None)."""

    def peak(results: Any) -> float:
        values = results.sensor(sensor).column(column)
        return float(np.max(np.abs(values)))

    peak.__name__ = f"peak_abs({sensor})"
    return peak


def final(sensor: str, column: Optional[Union[int, str]] = 0) -> Output:
    """An output: a sensor column's value at the last output time."""

    def last(results: Any) -> float:
        return float(np.asarray(results.sensor(sensor).column(column)).reshape(-1)[-1])

    last.__name__ = f"final({sensor})"
    return last


def summary_value(*path: str) -> Output:
    """An output: a number from the run's summary dict, by its keys (``summary_value("dynamic",
    "steps")``)."""

    def value(results: Any) -> float:
        v: Any = results.summary
        for p in path:
            v = v[p]
        return float(v)

    value.__name__ = "summary_value(" + ".".join(path) + ")"
    return value


@dataclass(frozen=True)
class SweepCase:
    """One case of a sweep, as sent to a worker (plain data: it is pickled)."""

    index: int
    study_text: str
    study_origin: str
    base_dir: str
    values: Variant
    outputs: Mapping[str, Output]
    analysis: Optional[str]
    results_dir: str
    cache_dir: str
    reduce_only: bool = False


def _load_case_study(case: SweepCase):
    from . import Study

    study = Study.from_toml(case.study_text, base_dir=case.base_dir, name=Path(case.study_origin).name)
    if case.values:
        study.update(case.values)
    return study


def _run_case(case: SweepCase) -> Dict[str, Any]:
    """Runs one case in a worker; never raises (the error goes into the row)."""
    started = time.perf_counter()
    row: Dict[str, Any] = {"case": case.index}
    row.update(case.values)
    for name in case.outputs:
        row[name] = math.nan
    row["error"] = None
    try:
        study = _load_case_study(case)
        if case.reduce_only:
            study.reduce(cache=case.cache_dir)
        else:
            results = study.run(case.analysis, results_dir=case.results_dir, cache=case.cache_dir)
            for name, fn in case.outputs.items():
                row[name] = float(fn(results))
    except Exception as e:  # noqa: BLE001: a sweep records every failure in its row
        row["error"] = f"{type(e).__name__}: {e}"
        row["traceback"] = traceback.format_exc()
    row["seconds"] = time.perf_counter() - started
    return row


def _parts_key(values: Variant) -> tuple:
    """The values of a variant that can change a reduced body (keys under ``parts.``)."""
    return tuple(sorted((k, repr(v)) for k, v in values.items() if k.startswith("parts.")))


def _table(rows: List[Dict[str, Any]], columns: List[str], as_pandas: Optional[bool]):
    if as_pandas is None:
        try:
            import pandas  # noqa: F401

            as_pandas = True
        except ImportError:
            as_pandas = False
    if as_pandas:
        import pandas as pd

        return pd.DataFrame(rows, columns=columns)
    table = {}
    for c in columns:
        values = [r.get(c) for r in rows]
        try:
            table[c] = np.asarray(values)
        except Exception:  # noqa: BLE001: mixed types stay a list
            table[c] = values
    return table


def sweep(
    study: Union[str, os.PathLike, Any],
    variants: Iterable[Variant],
    outputs: Mapping[str, Output],
    *,
    client: Any = "local",
    analysis: Optional[str] = None,
    results_dir: Optional[Union[str, os.PathLike]] = None,
    cache: Optional[Union[str, os.PathLike]] = None,
    n_workers: int = 2,
    as_pandas: Optional[bool] = None,
):
    """Runs every variant of ``study`` and returns a table with one row per case.

    - ``study``: a study file path, or a ``flexmbs.Study`` (its text and folder are sent).
    - ``variants``: dicts of key path to value (``grid(...)`` makes a Cartesian product).
    - ``outputs``: column name to a function of a case's ``Results`` giving a number
      (``peak_abs("midpoint")``, ``final("slider", 0)``, ``summary_value(...)``, or your own;
      it runs in the worker and must be picklable by cloudpickle, lambdas are).
    - ``client``: a ``dask.distributed.Client`` (any cluster), ``"local"`` (the default: a
      ``LocalCluster`` of ``n_workers`` single-threaded worker processes, closed at the end), or
      ``None`` (serial, in this process, no Dask needed).
    - ``analysis``: the analysis to run in each case (default: all of them).
    - ``results_dir``: each case writes into ``<results_dir>/case-NNNN`` (default: a
      ``sweep-results`` folder beside the study).
    - ``cache``: the reduced-body cache shared by all cases (default: the study's own,
      ``.flexmbs-cache`` beside the study file). On a real cluster it must be a folder every
      worker sees (a shared file system); otherwise each worker reduces for itself.

    Columns: ``case``, the variant keys, the outputs, ``error`` (``None`` when the case ran),
    ``seconds`` (wall time of the case in its worker) and ``traceback``. Rows are in the order of
    ``variants``. A pandas DataFrame when pandas is importable (``as_pandas``), else a dict of
    numpy arrays.
    """
    from . import Study

    if isinstance(study, (str, os.PathLike)):
        path = Path(study)
        text = path.read_text()
        origin = str(path)
        base_dir = str(path.resolve().parent)
    elif isinstance(study, Study):
        text, origin, base_dir = study.text, study.path, study.base_dir
    else:
        raise TypeError(f"sweep: study must be a path or a flexmbs.Study, got {type(study).__name__}")
    variants = [dict(v) for v in variants]
    if not variants:
        raise ValueError("sweep: no variants")
    for i, v in enumerate(variants):
        if not isinstance(v, dict):
            raise TypeError(f"sweep: variant {i} is not a dict of key paths to values: {v!r}")
    outputs = dict(outputs)
    for name, fn in outputs.items():
        if not callable(fn):
            raise TypeError(f"sweep: output {name!r} is not callable")
    results_root = Path(results_dir) if results_dir is not None else Path(base_dir) / "sweep-results"
    cache_dir = str(Path(cache) if cache is not None else Path(base_dir) / ".flexmbs-cache")
    results_root.mkdir(parents=True, exist_ok=True)

    def case(i: int, values: Variant, reduce_only: bool = False) -> SweepCase:
        return SweepCase(
            index=i,
            study_text=text,
            study_origin=origin,
            base_dir=base_dir,
            values=values,
            outputs=outputs,
            analysis=analysis,
            results_dir=str(results_root / f"case-{i:04d}"),
            cache_dir=cache_dir,
            reduce_only=reduce_only,
        )

    cases = [case(i, v) for i, v in enumerate(variants)]
    # First wave: one reduction per distinct set of part values, so that the cases that share
    # a reduced body do not all reduce it at once.
    first: Dict[tuple, int] = {}
    for i, v in enumerate(variants):
        first.setdefault(_parts_key(v), i)
    reductions = [case(i, variants[i], reduce_only=True) for i in first.values()]

    own_cluster = None
    if client == "local":
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as e:
            raise ImportError(
                'sweep: client="local" needs Dask distributed (pip install "flexmbs[sweep]"); '
                "pass client=None to run the cases serially"
            ) from e
        own_cluster = LocalCluster(
            n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(own_cluster)
    try:
        if client is None:
            for r in reductions:
                _run_case(r)
            rows = [_run_case(c) for c in cases]
        else:
            _gather(client, reductions)
            rows = _gather(client, cases)
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()
    columns = ["case", *_ordered_keys(variants), *outputs, "error", "seconds", "traceback"]
    for r in rows:
        r.setdefault("traceback", None)
    return _table(rows, columns, as_pandas)


def _gather(client: Any, cases: List[SweepCase]) -> List[Dict[str, Any]]:
    """Submits the cases and collects their rows; a worker that dies or a case that cannot be
    sent gives an error row instead of stopping the sweep."""
    futures = client.map(_run_case, cases, pure=False)
    rows = []
    for c, f in zip(cases, futures):
        try:
            rows.append(f.result())
        except Exception as e:  # noqa: BLE001
            row: Dict[str, Any] = {"case": c.index, **c.values}
            for name in c.outputs:
                row[name] = math.nan
            row["error"] = f"{type(e).__name__}: {e}"
            row["seconds"] = math.nan
            row["traceback"] = None
            rows.append(row)
    return rows


def _ordered_keys(variants: List[Variant]) -> List[str]:
    seen: Dict[str, None] = {}
    for v in variants:
        for k in v:
            seen.setdefault(k, None)
    return list(seen)
