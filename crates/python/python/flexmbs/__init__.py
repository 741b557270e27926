"""flexmbs: flexible multibody dynamics with superelements, from Python.

- ``Study``: a study file (the format of the ``flexmbs`` program) loaded from a file or TOML
  text; values read and changed by key path with the program's validation; ``run`` returns
  ``Results`` (sensors, tables, summary as numpy arrays and dicts); ``reduce`` gives the reduced
  bodies; ``simulation`` starts a dynamic analysis to step from Python.
- ``Simulation``: ``step``, ``advance_to``, sensors and state between steps, ``set_load``.
- ``ForceLaw``: a Python function of the time and joint coordinates giving actuator efforts
  and point loads inside the implicit step (``Study.run(forces=...)``,
  ``Study.simulation(forces=...)``).
- ``ReducedBody``: a reduced-body file (``.rbody``) and its matrices, modes and mass data.
- ``inspect(path)``: what a reduced body (``.rbody``, MBDyn ``.fem``, Matrix Market matrices)
  holds and its physical checks, as ``flexmbs inspect`` reports them (an ``Inspection``).
- Errors: ``FlexmbsError`` and its subclasses ``StudyError``, ``KeyPathError``,
  ``SolveError``, ``ReducedBodyFileError`` and ``UnknownNameError`` (also a ``KeyError``: an
  analysis or sensor name that is not there, with the close names).
- ``study_keys()``: every study-file key with its type, unit, default, range and doc.
- ``sweep``: many variants of a study in parallel on Dask distributed (optional dependency).

The classes come from the compiled extension ``flexmbs._flexmbs`` (Rust, PyO3). The API
reference and worked examples are in docs/python.md of the repository.
"""

from ._flexmbs import (  # noqa: F401
    FlexmbsError,
    ForceLaw,
    Inspection,
    KeyPathError,
    ReducedBody,
    ReducedBodyFileError,
    Simulation,
    SolveError,
    Study,
    StudyError,
    UnknownNameError,
    __version__,
    inspect,
    study_keys,
)
from .results import AnalysisResult, Page, Results, Sensor, Table  # noqa: F401
from .sweep import final, grid, peak_abs, summary_value, sweep  # noqa: F401

__all__ = [
    "AnalysisResult",
    "FlexmbsError",
    "ForceLaw",
    "Inspection",
    "KeyPathError",
    "Page",
    "ReducedBody",
    "ReducedBodyFileError",
    "Results",
    "Sensor",
    "Simulation",
    "SolveError",
    "Study",
    "StudyError",
    "Table",
    "UnknownNameError",
    "__version__",
    "final",
    "grid",
    "inspect",
    "peak_abs",
    "study_keys",
    "summary_value",
    "sweep",
]
