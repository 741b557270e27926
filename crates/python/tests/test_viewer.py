"""The results page `view.html` in a real browser (headless Chromium through Playwright): it
loads from file:// with no console error and no network request, draws the model, and the
positions and stresses it shows equal the run's VTU files.

Playwright drives the system's Chromium (/usr/bin/chromium, Debian's `chromium` package, or
$FLEXMBS_CHROMIUM); it never downloads a browser. Without Playwright or Chromium these tests
are skipped here, and `.ci/run` fails before running them. $FLEXMBS_SCREENSHOTS=DIR saves the
pages' screenshots there (docs/images/viewer-*.png are made so)."""

import math
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

REQUIRED = os.environ.get("FLEXMBS_REQUIRE_BROWSER") == "1"
try:
    import playwright.sync_api as playwright
except ImportError:
    if REQUIRED:
        raise
    pytest.skip("Playwright is not installed (pip install playwright)", allow_module_level=True)

CHROMIUM = Path(os.environ.get("FLEXMBS_CHROMIUM", "/usr/bin/chromium"))
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    # WebGL on the CPU: headless Chromium without a GPU.
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]
API = "window.flexmbsViewer"


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.is_file():
        (pytest.fail if REQUIRED else pytest.skip)(f"no Chromium at {CHROMIUM} (apt-get install chromium, or set FLEXMBS_CHROMIUM)")
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=ARGS)
        yield b
        b.close()


class Page:
    """A results page open in the browser, with its console messages and requests."""

    def __init__(self, browser, path: Path):
        self.page = browser.new_page(viewport={"width": 900, "height": 520})
        self.errors = []
        self.requests = []
        self.page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(path.resolve().as_uri())
        self.page.wait_for_function(f"{API} && {API}.ready", timeout=20000)

    def __call__(self, js: str):
        return self.page.evaluate(f"(() => {{ const v = {API}; return {js}; }})()")

    def node_position(self, body: int, node: int):
        """The position of mesh node `node` of `body`: the mean of its vertices (a solid
        node's one vertex, a beam node's rings, whose offsets cancel)."""
        vs = self(f"v.verticesOfNode({body}, {node})")
        assert vs, f"body {body} draws no vertex at node {node}"
        return np.mean([self(f"v.vertexPosition({body}, {i})") for i in vs], axis=0)

    def check_clean(self):
        assert not self.errors, f"console errors: {self.errors}"
        remote = [u for u in self.requests if not u.startswith(("file:", "data:", "blob:"))]
        assert not remote, f"network requests: {remote}"

    def check_drawn(self):
        """The canvas shows something: its pixels are not all the background's."""
        png = self.page.locator("#view").screenshot()
        from io import BytesIO

        matplotlib_image = pytest.importorskip("matplotlib.image")
        pixels = matplotlib_image.imread(BytesIO(png))[..., :3]
        background = pixels[0, 0]
        differ = np.abs(pixels - background).sum(axis=-1) > 0.05
        assert differ.mean() > 0.005, f"the canvas is blank ({differ.mean():.4f} of its pixels drawn)"

    def screenshot(self, name: str):
        folder = os.environ.get("FLEXMBS_SCREENSHOTS")
        if folder:
            Path(folder).mkdir(parents=True, exist_ok=True)
            self.page.screenshot(path=str(Path(folder) / f"viewer-{name}.png"))


def vtu(path: Path):
    """Points and point fields of a VTU file written by flexmbs (ASCII)."""
    text = path.read_text()

    def array(open_tag):
        m = re.search(open_tag + r"[^>]*>([^<]*)<", text)
        return np.array(m.group(1).split(), dtype=float) if m else None

    points = array(r'<Points>\s*<DataArray type="Float64" NumberOfComponents="3"').reshape(-1, 3)
    fields = {}
    for name in re.findall(r'<DataArray type="Float64" Name="([a-z_]+)"', text):
        fields[name] = array(rf'<DataArray type="Float64" Name="{name}"')
    return points, fields


def pvd(path: Path):
    return [(float(t), path.parent / f) for t, f in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', path.read_text())]


@pytest.fixture(scope="module")
def slider_crank(tmp_path_factory):
    """The built-in example (the flexible slider-crank), a short run."""
    from conftest import cli_path

    path = cli_path()
    if path is None:
        pytest.fail("the flexmbs program is not built: cargo build --release -p flexmbs, or set FLEXMBS_CLI")
    out = tmp_path_factory.mktemp("sc") / "results"
    import subprocess

    # In its own folder: the built-in example keeps its cache in the current folder.
    done = subprocess.run(
        [str(path), "run", "--out", str(out), "--t-end", "0.03"], capture_output=True, text=True, cwd=out.parent
    )
    assert done.returncode == 0, done.stderr
    return out


@pytest.fixture(scope="module")
def solid_bar(tmp_path_factory):
    """examples/solid_bar.toml: a static analysis with stresses, free-free modes, reductions."""
    from conftest import EXAMPLES, cli_path

    dst = tmp_path_factory.mktemp("sb") / "examples"
    shutil.copytree(EXAMPLES, dst, ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results", "__pycache__"))
    import subprocess

    done = subprocess.run([str(cli_path()), "run", str(dst / "solid_bar.toml")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return dst / "solid_bar-results"


def test_the_slider_crank_moves_as_its_vtu_files_say(browser, slider_crank):
    page = Page(browser, slider_crank / "view.html")
    page.check_clean()
    page.check_drawn()
    assert page("v.analyses()") == ["run-up"]
    series = pvd(slider_crank / "run-up" / "mechanism.pvd")
    assert page("v.frameCount()") == len(series) > 2
    assert np.allclose(page("v.frameKeys()"), [t for t, _ in series], rtol=0, atol=1e-12)
    bodies = page("v.bodies()")
    size = None
    for k in [0, len(series) // 2, len(series) - 1]:
        t, file = series[k]
        # Moving the slider moves the bodies: the frame at the slider's position is shown.
        page.page.eval_on_selector("#slider", "(e, k) => { e.value = k; e.dispatchEvent(new Event('input')); }", k)
        assert page("v.frame()") == k
        assert page("v.time()") == pytest.approx(t, abs=1e-12)
        points, fields = vtu(file)
        where = points + fields["displacement"].reshape(-1, 3)
        size = size or np.ptp(points, axis=0).max()
        body_of = fields["body"]
        for j, name in enumerate(bodies):
            first = int(np.argmax(body_of == j))
            count = int((body_of == j).sum())
            nodes = sorted({page(f"v.nodeOfVertex({j}, {i})") for i in range(0, page(f"v.vertexCount({j})"), 7)})
            assert nodes, name
            for n in nodes[:: max(1, len(nodes) // 6)]:
                assert n < count
                shown = page.node_position(j, n)
                # float32 vertices and shapes: a few parts in 10^7 of the model's size.
                assert np.allclose(shown, where[first + n], rtol=0, atol=2e-6 * size), (name, n, t, shown, where[first + n])
    # The slider's point, read back from the page, is where the sensor 'slider' says.
    sensor = np.loadtxt(slider_crank / "run-up" / "slider.csv", delimiter=",", skiprows=1, ndmin=2)
    for k in [1, len(series) - 1]:
        t = series[k][0]
        row = sensor[np.argmin(np.abs(sensor[:, 0] - t))]
        assert row[0] == pytest.approx(t, abs=1e-12)
        page(f"v.setTime({t})")
        drawn = [
            page(f"v.vertexPosition({j}, {i})")
            for j in range(len(bodies))
            for i in range(page(f"v.vertexCount({j})"))
            if page(f"v.vertexCount({j})") < 10
        ]
        gap = min(np.linalg.norm(np.array(p) - row[1:4]) for p in drawn)
        assert gap < 2e-6 * size, (t, row, gap)
    # Between frames the drawing moves.
    page("v.setFrame(0)")
    a = page.node_position(0, page("v.nodeOfVertex(0, 0)"))
    page(f"v.setFrame({len(series) - 1})")
    b = page.node_position(0, page("v.nodeOfVertex(0, 0)"))
    assert np.linalg.norm(a - b) > 1e-3 * size
    page.screenshot("slider-crank")
    page.check_clean()


def test_the_page_multisamples_on_a_gpu_and_not_on_a_software_rasteriser(browser, slider_crank):
    page = Page(browser, slider_crank / "view.html")
    r = page("v.rendering()")
    # What the browser's WebGL reports, read here independently of the page.
    name = page.page.evaluate(
        "() => { const c = document.createElement('canvas').getContext('webgl2');"
        " const e = c.getExtension('WEBGL_debug_renderer_info');"
        " return c.getParameter(e ? e.UNMASKED_RENDERER_WEBGL : c.RENDERER); }"
    )
    assert r["webgl"] == name
    software = any(s in name.lower() for s in ("swiftshader", "llvmpipe", "softpipe", "software"))
    assert r["software"] == software
    # The drawing context the page made has the multisampling it reports.
    made = page.page.evaluate("() => document.getElementById('view').getContext('webgl2').getContextAttributes().antialias")
    assert made == r["antialias"] == (not software)
    page.check_clean()


def test_the_stress_at_a_node_is_the_vtu_von_mises(browser, solid_bar):
    page = Page(browser, solid_bar / "view.html")
    page.check_clean()
    assert "bar-bending" in page("v.analyses()")
    page("v.select('bar-bending')")
    page("v.setColor('von-mises')")
    page("v.setView('iso')")
    page.check_drawn()
    points, fields = vtu(solid_bar / "bar-bending" / "static.vtu")
    vm = fields["von_mises"]
    u = fields["displacement"].reshape(-1, 3)
    n_vertices = page("v.vertexCount(0)")
    nodes = sorted({page(f"v.nodeOfVertex(0, {i})") for i in range(n_vertices)})
    checked = 0
    for n in nodes[:: max(1, len(nodes) // 12)]:
        [i] = page(f"v.verticesOfNode(0, {n})")
        # The value under the pointer is in MPa, the VTU's in Pa.
        shown = page(f"v.value(0, {i})")
        assert shown == pytest.approx(vm[n] / 1e6, rel=2e-5, abs=1e-6 * vm.max() / 1e6), (n, shown, vm[n])
        # A static displacement is drawn at its size (scale factor 1).
        assert np.allclose(page(f"v.vertexPosition(0, {i})"), points[n] + u[n], rtol=0, atol=2e-7)
        checked += 1
    assert checked >= 6
    # The value under the pointer: the bar is in the middle of the view.
    box = page.page.locator("#view").bounding_box()
    page.page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    probe = page.page.locator("#probe").text_content()
    # The node's label in the mesh file (gmsh's node number) and its index in the VTU.
    assert re.search(r"body part, node \d+ \(index \d+\)", probe), probe
    assert re.search(r"von Mises [-0-9.e]+ MPa", probe) and "position (" in probe, probe
    page.screenshot("solid-bar-stress")
    page.check_clean()


def test_the_mode_shapes_animate_with_their_frequencies(browser, solid_bar):
    page = Page(browser, solid_bar / "view.html")
    page("v.select('block-free')")
    freqs = np.loadtxt(solid_bar / "block-free" / "frequencies.csv", delimiter=",", skiprows=1, usecols=1, ndmin=1)
    modes = page("v.modes()")
    assert len(modes) == len(freqs) == 8
    assert np.allclose([m["frequency"] for m in modes], freqs, rtol=1e-12, atol=1e-9)
    assert [m["label"] for m in modes] == [f"mode {k}" for k in range(1, 9)]
    # Mode 7 (the first bending mode): the drawn displacement is the VTU's mode shape, scaled.
    page("v.setMode(6)")
    page("v.pause()")
    points, fields = vtu(solid_bar / "block-free" / "mode_007.vtu")
    shape = fields["displacement"].reshape(-1, 3)
    page(f"v.setPhase({math.pi / 2})")
    nodes = sorted({page(f"v.nodeOfVertex(0, {i})") for i in range(0, page("v.vertexCount(0)"), 3)})
    drawn = np.array([page.node_position(0, n) for n in nodes]) - points[nodes]
    ratio = np.sum(drawn * shape[nodes]) / np.sum(shape[nodes] ** 2)
    assert ratio > 0
    assert np.allclose(drawn, ratio * shape[nodes], rtol=0, atol=1e-5 * np.abs(drawn).max())
    # Playing moves the shape: two reads apart in time differ.
    page("v.play()")
    before = page.node_position(0, nodes[-1])
    page.page.wait_for_timeout(300)
    after = page.node_position(0, nodes[-1])
    assert page("v.playing()")
    assert np.linalg.norm(after - before) > 1e-4 * np.abs(drawn).max()
    page.screenshot("modes")
    page.check_drawn()
    page.check_clean()


def test_a_mechanisms_linearised_modes_animate_about_its_equilibrium(browser, tmp_path):
    """examples/four_bar.toml: every mode of the linearised analysis about the equilibrium,
    with the frequencies of its table; each mode's drawing moves away from the equilibrium by
    the page's tenth of the model's size."""
    import subprocess

    from conftest import EXAMPLES, cli_path

    dst = tmp_path / "examples"
    shutil.copytree(EXAMPLES, dst, ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results", "__pycache__"))
    done = subprocess.run([str(cli_path()), "run", str(dst / "four_bar.toml"), "--t-end", "0.01"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    res = dst / "four_bar-results"
    page = Page(browser, res / "view.html")
    page("v.select('linearized')")
    freqs = np.loadtxt(res / "linearized" / "frequencies.csv", delimiter=",", skiprows=1, usecols=1, ndmin=1)
    modes = page("v.modes()")
    assert len(modes) == len(freqs) == 6
    assert np.allclose([m["frequency"] for m in modes], freqs, rtol=1e-12)
    page("v.pause()")
    n_bodies = len(page("v.bodies()"))

    def drawn():
        return np.concatenate(
            [[page(f"v.vertexPosition({j}, {i})") for i in range(0, page(f"v.vertexCount({j})"), 3)] for j in range(n_bodies)]
        )

    for k in range(len(modes)):
        page(f"v.setMode({k})")
        page("v.setPhase(0)")
        rest = drawn()
        page(f"v.setPhase({math.pi / 2})")
        moved = drawn()
        size = np.ptp(rest, axis=0).max()
        assert 0.02 * size < np.linalg.norm(moved - rest, axis=1).max() < 0.2 * size, k
    page.check_drawn()
    page.check_clean()
