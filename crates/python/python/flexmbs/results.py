"""Results of a study run as numpy arrays: ``Results`` (the run), ``AnalysisResult`` (one
analysis), ``Sensor`` (one sensor's time column and value columns with names and units).

``Study.run`` returns a ``Results``; the same numbers are in the results folder the run wrote
(CSV files with the same values, ``summary.json`` with the same summary).
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Union

import numpy as np

from ._flexmbs import _unknown_name_error

__all__ = ["Results", "AnalysisResult", "Sensor", "Table"]


def _split_unit(label: str):
    """``"deflection [m]"`` -> ``("deflection", "m")``; no unit -> ``(label, "")``."""
    if label.endswith("]") and " [" in label:
        name, unit = label.rsplit(" [", 1)
        return name, unit[:-1]
    return label, ""


class Sensor:
    """One sensor of an analysis: ``time`` (the abscissa: time [s], or the load factor of an
    equilibrium), ``values`` (samples x columns), ``columns`` (names), ``units``."""

    def __init__(self, name: str, x_label: str, x: np.ndarray, labels: List[str], values: np.ndarray):
        self.name = name
        self.x_label = x_label
        self.time = x
        self.labels = list(labels)
        self.columns = [_split_unit(c)[0] for c in labels]
        self.units = [_split_unit(c)[1] for c in labels]
        self.values = values

    def column(self, which: Union[int, str, None] = None) -> np.ndarray:
        """Column ``which`` (index, or name with or without its unit) as a 1-D array; all
        columns (2-D) when None."""
        if which is None:
            return self.values
        if isinstance(which, str):
            for k, (c, label) in enumerate(zip(self.columns, self.labels)):
                if which in (c, label):
                    return self.values[:, k]
            raise KeyError(f"sensor {self.name!r} has no column {which!r}; it has {self.labels}")
        return self.values[:, which]

    def __repr__(self) -> str:
        return f"Sensor({self.name!r}, {len(self.time)} samples, columns={self.labels})"


class Table:
    """A result table (``frequencies``, ``modes``, ``displacements``, ...): ``columns`` (with
    units) and ``data`` (column name -> numpy array, or a list for text columns)."""

    def __init__(self, name: str, columns: List[str], data: Dict[str, Any]):
        self.name = name
        self.columns = list(columns)
        self.data = data

    def __getitem__(self, column: str):
        if column in self.data:
            return self.data[column]
        for label in self.columns:
            if _split_unit(label)[0] == column:
                return self.data[label]
        raise KeyError(f"table {self.name!r} has no column {column!r}; it has {self.columns}")

    def __repr__(self) -> str:
        n = len(next(iter(self.data.values()))) if self.data else 0
        return f"Table({self.name!r}, {n} rows, columns={self.columns})"


class AnalysisResult:
    """What one analysis produced: ``sensors`` (name -> Sensor), ``tables`` (name -> Table),
    ``summary`` (its entry of summary.json, a dict); for a linearised analysis
    ``frequencies`` [Hz] and ``mode_labels``."""

    def __init__(self, raw: Dict[str, Any]):
        self.name: str = raw["name"]
        self.kind: str = raw["kind"]
        self.summary: Optional[Dict[str, Any]] = raw.get("summary")
        self.tables: Dict[str, Table] = {t["name"]: Table(t["name"], t["columns"], t["data"]) for t in raw["tables"]}
        self.sensors: Dict[str, Sensor] = {}
        s = raw.get("sensors")
        if s is not None:
            for g in s["groups"]:
                self.sensors[g["name"]] = Sensor(g["name"], s["x_label"], s["x"], g["columns"], g["values"])

    def sensor(self, name: str) -> Sensor:
        """Sensor ``name``; ``UnknownNameError`` (a ``KeyError``) with the close names when
        this analysis did not record it."""
        try:
            return self.sensors[name]
        except KeyError:
            raise _unknown_name_error("sensor", name, list(self.sensors)) from None

    @property
    def frequencies(self) -> Optional[np.ndarray]:
        """Frequencies [Hz] of a modal or linearised analysis (None for others)."""
        results = (self.summary or {}).get("results") or {}
        for key in ("frequencies_hz", "frequencies"):
            if key in results:
                return np.asarray(results[key], dtype=float)
        for t in self.tables.values():
            for label in t.columns:
                if label.startswith("f [Hz]") or label.startswith("frequency [Hz]"):
                    return np.asarray(t.data[label], dtype=float)
        return None

    @property
    def mode_labels(self) -> Optional[List[str]]:
        """Each mode's label of a linearised analysis (the body and node carrying most of its
        energy), as in modes.csv and summary.json."""
        results = (self.summary or {}).get("results") or {}
        if "mode_labels" in results:
            return list(results["mode_labels"])
        return None

    def __repr__(self) -> str:
        return f"AnalysisResult({self.name!r}, kind={self.kind!r}, sensors={sorted(self.sensors)}, tables={sorted(self.tables)})"


class Results:
    """A study run: ``analyses`` (name -> AnalysisResult, in run order), ``summary`` (the dict of
    summary.json), ``results_dir`` (the folder the run wrote), ``messages`` (progress notes such
    as cache hits)."""

    def __init__(self, raw: Dict[str, Any]):
        self.results_dir: str = raw["results_dir"]
        self.summary: Optional[Dict[str, Any]] = raw.get("summary")
        self.messages: List[str] = list(raw.get("messages", []))
        self.analyses: Dict[str, AnalysisResult] = {}
        for a in raw["analyses"]:
            self.analyses[a["name"]] = AnalysisResult(a)

    def __getitem__(self, analysis: str) -> AnalysisResult:
        """Analysis ``analysis``; ``UnknownNameError`` (a ``KeyError``) with the close names
        when these results do not hold it."""
        try:
            return self.analyses[analysis]
        except KeyError:
            raise _unknown_name_error("analysis", analysis, list(self.analyses)) from None

    def sensor(self, name: str, analysis: Optional[str] = None) -> Sensor:
        """Sensor ``name`` of ``analysis`` (default: the last analysis that recorded it);
        ``UnknownNameError`` (a ``KeyError``) with the close names for a sensor no analysis
        recorded, or an analysis these results do not hold."""
        if analysis is not None:
            return self[analysis].sensor(name)
        for a in reversed(list(self.analyses.values())):
            if name in a.sensors:
                return a.sensors[name]
        recorded = sorted({s for a in self.analyses.values() for s in a.sensors})
        raise _unknown_name_error("sensor", name, recorded)

    def __repr__(self) -> str:
        return f"Results({list(self.analyses)}, results_dir={self.results_dir!r})"
