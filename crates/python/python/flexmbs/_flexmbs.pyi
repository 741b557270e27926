"""Type stubs of the compiled extension ``flexmbs._flexmbs`` (Rust, PyO3: crates/python/src).

Every name the extension exports is declared here, and only those: tests/test_stubs.py checks
both ways, and type-checks a sample script against these stubs with mypy. The read-only
properties of the classes are declared ``Final`` attributes: mypy refuses an assignment.
"""

import os
from typing import Any, Dict, Final, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from .results import Results

_Path = Union[str, "os.PathLike[str]"]
_Vec3 = Union[Sequence[float], npt.NDArray[np.float64]]
_Array = npt.NDArray[np.float64]

__version__: str

class FlexmbsError(Exception):
    """Base class of every error raised by flexmbs."""

class ReducedBodyFileError(FlexmbsError):
    """A reduced-body file (.rbody) could not be read or written; ``path`` names it."""

    path: str

class StudyError(FlexmbsError):
    """A study is not valid; ``file``, ``line``, ``column`` and ``key`` locate the first error,
    ``errors`` lists all (dicts of these and ``message``)."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]
    errors: List[Dict[str, Any]]

class KeyPathError(FlexmbsError):
    """A key path that leads to no value of the study; ``path`` is the path, ``at`` its part that
    leads nowhere."""

    path: str
    at: str

class SolveError(FlexmbsError):
    """A solver stopped: ``time`` (dynamic) or ``load_factor`` (equilibrium), ``step``,
    ``residual`` and ``analysis`` say where, ``file``, ``line``, ``column`` and ``key`` the
    study's entity it failed at (None when not known); ``partial`` holds the ``Results`` that
    ``Study.run`` computed before."""

    time: Optional[float]
    load_factor: Optional[float]
    step: Optional[int]
    residual: Optional[float]
    analysis: Optional[str]
    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]
    partial: Optional[Results]

class UnknownNameError(FlexmbsError, KeyError):
    """A name the study or the results do not have (an analysis, a sensor); the message says
    which names are close. ``name``, ``what`` (``"analysis"``, ``"sensor"``), ``matches`` (the
    close names) and ``defined`` (every name there is)."""

    name: str
    what: str
    matches: List[str]
    defined: List[str]

def _unknown_name_error(what: str, name: str, defined: List[str]) -> UnknownNameError:
    """The ``UnknownNameError`` for ``name`` among the ``defined`` names of a ``what`` (for the
    pure-Python part of the package to raise)."""

def study_keys(table: Optional[str] = None) -> List[Dict[str, Any]]:
    """The keys of a study file, one dict each: ``table`` (dotted table path, ``""`` for the
    file's root), ``name``, ``kinds`` (the kinds of the table that take it; empty: all),
    ``type``, ``unit``, ``required``, ``default`` (as the docs write it; ``""`` when none),
    ``range`` and ``doc``. With ``table``, only that table's keys. The same declarations give
    the validator's allowed keys and the key tables of docs/study-file.md."""

class ReducedBody:
    """A reduced flexible body: interfaces, reduced matrices, mass data, fixed-interface modes.
    ``ReducedBody.load(path)`` reads a ``.rbody`` file; every array property returns a fresh
    numpy array."""

    @staticmethod
    def load(path: _Path) -> "ReducedBody":
        """Reads a reduced-body file; ``ReducedBodyFileError`` (with ``path``) when it is
        missing, damaged, of a newer format version or not a reduced body."""
    def save(self, path: _Path) -> None:
        """Writes the body to ``path`` (atomically); reading it back gives the same body."""
    name: Final[str]
    """The body's name (its part's name)."""
    format_version: Final[int]
    """Format version of the reduced-body data."""
    n_modes: Final[int]
    """Number m of fixed-interface modes."""
    n_coordinates: Final[int]
    """Number n = 6N + m of CB coordinates."""
    interfaces: Final[List[Dict[str, Any]]]
    """Interfaces in the order of the CB coordinates: dicts with ``name``, ``node`` and
    ``position``."""
    interface_names: Final[List[str]]
    """Names of the interfaces, in the order of the CB coordinates."""
    K_CB: Final[_Array]
    """The reduced stiffness matrix (n x n)."""
    M_CB: Final[_Array]
    """The reduced mass matrix (n x n)."""
    mass: Final[float]
    """Total mass [kg]."""
    center_of_mass: Final[_Array]
    """Centre of mass of the undeformed body, FE axes [m]."""
    inertia: Final[_Array]
    """Inertia tensor about the centre of mass, FE axes [kg m^2] (3x3)."""
    invariants: Final[Dict[str, _Array]]
    """The mass-field invariants: ``S_t``, ``S_r``, ``S_x``, ``S_bar``, ``Phi_com``."""
    fixed_interface_omega: Final[_Array]
    """Circular frequencies of the kept fixed-interface modes [rad/s], ascending."""
    fixed_interface_frequencies: Final[_Array]
    """Frequencies of the kept fixed-interface modes [Hz], ascending."""
    mesh_nodes: Final[Optional[_Array]]
    """Reference coordinates of the FE nodes (n_nodes x 3) [m], or None."""
    cb_basis: Final[Optional[_Array]]
    """The CB basis on the mesh (6 n_nodes x n), or None without mesh shapes."""
    mode_shapes: Final[Optional[_Array]]
    """The fixed-interface mode shapes on the mesh (n_nodes x 6 x m), or None."""
    geometric_stiffness: Final[Optional[_Array]]
    """The reduced geometric stiffness matrices G_k (n x n x n), or None."""
    def __eq__(self, other: object) -> bool: ...

class Study:
    """A study file held in memory, read and changed value by value through key paths
    (``parts.rod.reduction.modes``, ``sections[0].d``), validated as ``flexmbs check`` does
    after every change."""

    @staticmethod
    def load(path: _Path) -> "Study":
        """Reads and validates the study file at ``path``; ``StudyError`` when it is not
        valid."""
    @staticmethod
    def from_toml(text: str, base_dir: Optional[_Path] = None, name: Optional[str] = None) -> "Study":
        """A study from TOML ``text``; ``base_dir`` anchors its relative paths, ``name`` is the
        file name errors and the results folder use (default ``study.toml``)."""
    path: Final[str]
    """The study file this study came from (or the name it was given)."""
    base_dir: Final[str]
    """The folder relative paths of the study are taken from."""
    text: Final[str]
    """The study as TOML text now (comments and layout kept)."""
    analyses: Final[List[str]]
    """Names of the analyses, in the order they run."""
    parts: Final[List[str]]
    """Names of the parts."""
    def validate(self) -> None:
        """Checks the study as ``flexmbs check`` does; ``StudyError`` when it is not valid."""
    def get(self, key: str) -> Any:
        """The value at key path ``key`` (tables as dicts); ``KeyPathError`` for a path that
        leads nowhere."""
    def set(self, key: str, value: Any) -> None:
        """Sets the value at ``key`` and validates the study; a dict given to a table replaces
        the whole table. A refused value raises ``StudyError`` and is not kept."""
    def update(self, values: Dict[str, Any]) -> None:
        """Sets several values, then validates once; on an error none is kept."""
    def remove(self, key: str) -> None:
        """Removes the value or table at ``key`` and validates the study; a refused removal
        raises ``StudyError`` and is not kept."""
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def __delitem__(self, key: str) -> None: ...
    def _run(
        self,
        analysis: Optional[str] = None,
        results_dir: Optional[_Path] = None,
        cache: Optional[_Path] = None,
        t_end: Optional[float] = None,
    ) -> Dict[str, Any]:
        """``run`` returning the raw results that ``flexmbs.results.Results`` wraps."""
    def run(
        self,
        analysis: Optional[str] = None,
        results_dir: Optional[_Path] = None,
        cache: Optional[_Path] = None,
        t_end: Optional[float] = None,
    ) -> Results:
        """Runs the analyses (all, or the one named ``analysis``: ``UnknownNameError`` when
        there is none) as ``flexmbs run`` does; a solver failure raises ``SolveError`` whose
        ``partial`` holds the results computed before."""
    def reduce(self, part: Optional[str] = None, cache: Optional[_Path] = None) -> List[Tuple[str, ReducedBody]]:
        """Reduces the parts that have a ``[parts.reduction]`` (or the one named ``part``)
        through the cache; ``(part name, ReducedBody)`` pairs."""
    def simulation(
        self, analysis: Optional[str] = None, cache: Optional[_Path] = None, results_dir: Optional[_Path] = None
    ) -> "Simulation":
        """Starts the dynamic analysis ``analysis`` (default: the only dynamic one) for stepping
        from Python; ``UnknownNameError`` for a name the study does not have. With
        ``results_dir``, the simulation writes the analysis' results folder as it steps, until
        ``finish_results()``."""

class Simulation:
    """A dynamic analysis stepped from Python (``Study.simulation``)."""

    analysis: Final[str]
    """The analysis being stepped."""
    time: Final[float]
    """The time reached [s]."""
    dt: Final[float]
    """The analysis' step size [s]."""
    end_time: Final[float]
    """The analysis' end time [s]."""
    steps: Final[int]
    """Steps taken."""
    sensor_names: Final[List[str]]
    """The names of the study's sensors."""
    load_names: Final[List[str]]
    """The names of the study's point loads (those ``set_load`` can change)."""
    actuator_names: Final[List[str]]
    """The names of the study's actuators (those ``set_actuator`` can hold)."""
    def step(self, dt: Optional[float] = None) -> int:
        """One time step under the analysis' step control, as ``run()`` takes it (a failed fixed
        step retried with halved steps down to ``dt_min``, or one adaptive step); with ``dt``,
        one step of that size. Returns the Newton iterations it took (``SolveError`` on
        failure)."""
    def finish_results(self) -> Optional[Dict[str, Any]]:
        """Ends the results folder of a simulation started with ``results_dir``; returns its
        summary (``None`` without a folder or once ended)."""
    def advance_to(self, t: float) -> int:
        """Steps (as ``step()`` does) until the time reaches ``t``; returns the number of steps
        taken."""
    def sensor_columns(self, name: str) -> List[str]:
        """Column names (with units) of sensor ``name``."""
    def sensor(self, name: str) -> _Array:
        """The values of sensor ``name`` now; ``UnknownNameError`` for a name the study does
        not have."""
    def sensors(self) -> Dict[str, _Array]:
        """Every sensor now: ``{name: values}``."""
    def state(self) -> Dict[str, Any]:
        """The full state: ``time``, ``labels``, ``velocity``, ``acceleration``, ``scalars``,
        ``rotations``."""
    def node_motions(self) -> Dict[str, Any]:
        """Every node's motion: ``names``, ``position``, ``orientation``, velocities and
        accelerations."""
    def set_load(self, name: str, force: Optional[_Vec3] = None, moment: Optional[_Vec3] = None) -> None:
        """Sets the force [N] and/or moment [N m] of point load ``name`` from the next step on."""
    def set_actuator(self, name: str, effort: Optional[float]) -> None:
        """Holds actuator ``name`` at ``effort`` (None releases it) from the next step on."""
    def release_actuator(self, name: str) -> None:
        """Releases actuator ``name`` to its ``function`` or ``pid``."""
    def actuator_effort(self, name: str) -> float:
        """The effort [N or N m] actuator ``name`` applies now."""
    def held_actuator(self, name: str) -> Optional[float]:
        """The effort actuator ``name`` is held at, None while its law acts."""
