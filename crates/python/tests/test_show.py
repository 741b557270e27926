"""The Python side of the results page: `Results.show()` (inline in Jupyter), `Results.plot()`
(matplotlib) and `Study.show()` (the model before it runs), the pages checked in headless
Chromium as in test_viewer.py, and a notebook executed by nbclient."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from test_viewer import Page, browser  # noqa: F401 (the fixture)


@pytest.fixture(scope="module")
def flexmbs_package():
    return pytest.importorskip("flexmbs")


def test_results_show_and_plot_and_the_model_before_it_runs(browser, flexmbs_package, tmp_path):
    from conftest import EXAMPLES

    dst = tmp_path / "examples"
    shutil.copytree(EXAMPLES, dst, ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results", "__pycache__"))
    study = flexmbs_package.Study.load(dst / "slider_crank.toml")
    # The model before it runs: one frame, every body.
    before = study.show()
    assert isinstance(before, str) and before.path is None
    (tmp_path / "before.html").write_text(before)
    page = Page(browser, tmp_path / "before.html")
    page.check_clean()
    page.check_drawn()
    assert page("v.frameCount()") == 1
    assert len(page("v.bodies()")) == 6
    results = study.run(t_end=0.01)
    shown = results.show()
    assert shown == (Path(results.results_dir) / "view.html").read_text()
    assert "<iframe srcdoc=" in shown.iframe()
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    fig = results.plot("slider")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "t [s]"
    assert ax.get_ylabel() == "slider [m]"
    assert [line.get_label() for line in ax.get_lines()] == ["position_x [m]", "position_y [m]", "position_z [m]"]
    assert np.allclose(ax.get_lines()[0].get_ydata(), results.sensor("slider").values[:, 0])
    with pytest.raises(KeyError):
        results.plot("no-such-sensor")


def test_a_notebook_shows_the_results_page_inline(flexmbs_package, tmp_path):
    """A Jupyter notebook (executed by nbclient with the current interpreter's kernel) runs a
    study and shows its results page and a sensor plot inline."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    from conftest import EXAMPLES

    dst = tmp_path / "examples"
    shutil.copytree(EXAMPLES, dst, ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results", "__pycache__"))
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(
            "import flexmbs\n"
            f"study = flexmbs.Study.load({str(dst / 'slider_crank.toml')!r})\n"
            "results = study.run(t_end=0.01)\n"
            "page = results.show(height=400)"
        ),
        nbformat.v4.new_code_cell("%matplotlib inline\nfig = results.plot('slider')"),
    ]
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    shown = [o for o in nb.cells[0].outputs if o.get("output_type") == "display_data"]
    assert len(shown) == 1, nb.cells[0].outputs
    html = shown[0]["data"]["text/html"]
    assert html.startswith("<iframe srcdoc=") and "flexmbs-data" in html and "height:400px" in html
    pictures = [o for o in nb.cells[1].outputs if "image/png" in o.get("data", {})]
    assert pictures, nb.cells[1].outputs
