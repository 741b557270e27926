"""Results of a study run as numpy arrays: ``Results`` (the run), ``AnalysisResult`` (one
analysis), ``Sensor`` (one sensor's time column and value columns with names and units).

``Study.run`` returns a ``Results``; the same numbers are in the results folder the run wrote
(CSV files with the same values, ``summary.json`` with the same summary).
"""

from __future__ import annotations

import html as _html
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ._flexmbs import _unknown_name_error

__all__ = ["Results", "AnalysisResult", "Sensor", "Table", "Page"]


class Page(str):
    """The HTML text of a results page (``view.html``: one self-contained file, three.js
    inlined, no network request); ``path`` is where it is. Shown inline in Jupyter as an
    iframe."""

    path: Optional[str]

    def __new__(cls, text: str, path: Optional[str] = None):
        page = super().__new__(cls, text)
        page.path = path
        return page

    def __repr__(self) -> str:
        where = f" at {self.path}" if self.path else ""
        return f"<flexmbs results page{where}, {len(self)} characters>"

    def iframe(self, height: int = 560) -> str:
        """The page as an ``<iframe srcdoc=...>`` element for a notebook's output."""
        return (
            f'<iframe srcdoc="{_html.escape(str(self), quote=True)}" '
            f'style="width:100%;height:{int(height)}px;border:1px solid #ccd" '
            'sandbox="allow-scripts"></iframe>'
        )

    def show(self, height: int = 560) -> "Page":
        """Displays the page in Jupyter (IPython.display, when there is a notebook kernel)."""
        _display_page(self, height)
        return self


def _display_page(page: Page, height: int) -> None:
    try:
        from IPython import get_ipython
        from IPython.display import HTML, display
    except ImportError:
        return
    shell = get_ipython()
    if shell is None or not hasattr(shell, "kernel"):
        return
    display(HTML(page.iframe(height)))


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

    def show(self, height: int = 560) -> Page:
        """The results page of the run (``view.html`` of the results folder: the bodies moving,
        the mode shapes, stresses and sensors of every analysis), displayed inline in Jupyter
        when there is a notebook kernel; returns its HTML (a ``Page``, a ``str``). Open the
        file in a browser outside Jupyter."""
        path = Path(self.results_dir) / "view.html"
        if not path.is_file():
            raise FileNotFoundError(f"{path}: the run wrote no results page")
        page = Page(path.read_text(encoding="utf-8"), str(path))
        _display_page(page, height)
        return page

    def plot(self, sensor: str, analysis: Optional[str] = None, ax=None):
        """Plots sensor ``sensor`` (of ``analysis``, default as ``sensor``) with matplotlib
        (the optional extra ``flexmbs[plot]``): every column against time, one axis per unit,
        labelled with names and units. Returns the matplotlib ``Figure``; ``ax`` draws into an
        existing axis (all the columns on it)."""
        try:
            import matplotlib.pyplot as plt
        except ImportError as e:
            raise ImportError("Results.plot needs matplotlib: pip install 'flexmbs[plot]'") from e
        s = self.sensor(sensor, analysis)
        units = list(dict.fromkeys(s.units))
        if ax is None:
            fig, axes = plt.subplots(len(units), 1, sharex=True, squeeze=False, figsize=(7, 2.4 + 1.6 * len(units)))
            axes = [a[0] for a in axes]
        else:
            fig, axes = ax.figure, [ax] * len(units)
        for unit, a in zip(units, axes):
            for k, (name, u) in enumerate(zip(s.columns, s.units)):
                if u == unit:
                    a.plot(s.time, s.values[:, k], label=f"{name} [{u}]" if u else name)
            a.set_ylabel(f"{s.name} [{unit}]" if unit else s.name)
            a.grid(True, alpha=0.3)
            a.legend(loc="best", fontsize="small")
        axes[-1].set_xlabel(s.x_label)
        axes[0].set_title(f"sensor {s.name}")
        return fig

    def __repr__(self) -> str:
        return f"Results({list(self.analyses)}, results_dir={self.results_dir!r})"
