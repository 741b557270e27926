"""The type stubs of the extension (flexmbs/_flexmbs.pyi): shipped with the package, listing
exactly the names the extension exports (so they cannot drift from it), and good enough for
mypy to check a script against them."""

import ast
import inspect
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import flexmbs
import flexmbs._flexmbs as ext

STUBS = Path(flexmbs.__file__).with_name("_flexmbs.pyi")


def public(names):
    """Names without the dunders a module or class has anyway (``__version__`` is ours)."""
    return {n for n in names if not (n.startswith("__") and n.endswith("__")) or n == "__version__"}


def stub_tree():
    return ast.parse(STUBS.read_text())


def stub_module_names(tree):
    """What the stubs declare at module level: classes, functions, annotated variables (the
    private type aliases, plain assignments, are not exports)."""
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def test_the_stubs_are_shipped_with_the_package():
    assert STUBS.is_file()
    assert STUBS.with_name("py.typed").is_file()


def test_the_stubs_list_exactly_the_names_the_extension_exports():
    tree = stub_tree()
    assert stub_module_names(tree) == public(dir(ext))
    # And each class's methods and properties (an exception's attributes are set on each
    # raised instance, so they are checked by the tests that raise them).
    for node in tree.body:
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(ext, node.name)
        if issubclass(cls, BaseException):
            continue
        # Methods, and the read-only properties declared as `Final` attributes.
        declared = public(n.name for n in node.body if isinstance(n, ast.FunctionDef))
        declared |= {n.target.id for n in node.body if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
        assert declared == public(vars(cls)), node.name


def test_the_exported_functions_take_the_arguments_the_stubs_declare():
    for node in stub_tree().body:
        if isinstance(node, ast.FunctionDef):
            declared = [a.arg for a in node.args.args]
            assert list(inspect.signature(getattr(ext, node.name)).parameters) == declared, node.name


@pytest.fixture(scope="module")
def mypy_cache(tmp_path_factory):
    """One mypy cache for the module's runs (numpy's stubs are read once)."""
    return tmp_path_factory.mktemp("mypy-cache")


def mypy(tmp_path, cache, script):
    """mypy (strict) on `script` against the installed package; its exit code and report."""
    path = tmp_path / "sample.py"
    path.write_text(textwrap.dedent(script))
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-color-output", "--cache-dir", str(cache), str(path)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    return done.returncode, done.stdout + done.stderr


SAMPLE = """
    from typing import Dict, List, Optional

    import numpy as np
    import numpy.typing as npt

    import flexmbs


    def thicker_rod(path: str) -> float:
        study = flexmbs.Study.load(path)
        study["sections.rod.d"] = 0.008
        study["sections.rod"] = {"name": "rod", "shape": "circle", "d": 0.007}
        del study["analyses.run-up.rho_inf"]
        names: List[str] = study.analyses
        try:
            results: flexmbs.Results = study.run(analysis=names[0], t_end=0.01)
        except flexmbs.UnknownNameError as e:
            close: List[str] = e.matches
            raise KeyError(close) from e
        except flexmbs.SolveError as e:
            at: Optional[float] = e.time
            raise RuntimeError(at) from e
        sim: flexmbs.Simulation = study.simulation(cache="cache")
        sim.set_load("motor", moment=[0.0, 0.0, 1.0])
        steps: int = sim.advance_to(0.01)
        now: npt.NDArray[np.float64] = sim.sensor("rod-mid")
        every: Dict[str, npt.NDArray[np.float64]] = sim.sensors()
        body: flexmbs.ReducedBody = dict(study.reduce())["segment"]
        return float(now[0]) + body.mass + steps + len(every) + float(results.sensor("rod-mid").values[-1, 0])
"""


def test_mypy_accepts_a_script_that_uses_the_stubs_right(tmp_path, mypy_cache):
    code, report = mypy(tmp_path, mypy_cache, SAMPLE)
    assert code == 0, report


@pytest.mark.parametrize(
    "mistake, expected",
    [
        ('    steps_wrong: str = sim.advance_to(0.01)\n', "Incompatible types in assignment"),
        ('    study.run(analysis=3)\n', 'Argument "analysis" to "run" of "Study" has incompatible type "int"'),
        ('    sim.step(1.0)\n', 'Too many arguments for "step" of "Simulation"'),
    ],
)
def test_mypy_refuses_a_type_error_against_the_stubs(tmp_path, mypy_cache, mistake, expected):
    # The mistake goes into the sample's function body, before its `return`.
    body, ret = SAMPLE.rsplit("        return", 1)
    wrong = body + textwrap.indent(mistake, "    ") + "        return" + ret
    code, report = mypy(tmp_path, mypy_cache, wrong)
    assert code == 1, report
    assert expected in report, report
