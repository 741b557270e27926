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

from chromium import ARGS, CHROMIUM, MISSING  # noqa: E402 (after the skip above)

API = "window.flexmbsViewer"


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.is_file():
        (pytest.fail if REQUIRED else pytest.skip)(MISSING)
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


def srgb(linear):
    """The sRGB encoding (what the screen shows) of linear RGB values in [0, 1] (IEC 61966-2-1)."""
    x = np.asarray(linear, dtype=float)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def legend(page):
    """The legend as the page shows it: its title and the numbers at its ends."""
    return (
        page.page.locator("#legendTitle").text_content(),
        float(page.page.locator("#legendMin").text_content()),
        float(page.page.locator("#legendMax").text_content()),
    )


def legend_bar(page):
    """The RGB colours (0 to 1) of the legend bar's pixels, left to right."""
    rgb = page.page.evaluate(
        "() => { const c = document.getElementById('legendBar');"
        " return Array.from(c.getContext('2d').getImageData(0, 0, c.width, 1).data); }"
    )
    return np.array(rgb, dtype=float).reshape(-1, 4)[:, :3] / 255


def test_colour_by_displacement_and_stress_follows_the_legend_in_the_vtus_units(browser, solid_bar):
    """Each drawn vertex's colour is the legend bar's colour at its VTU value in the legend's
    units (mm, MPa), and the legend spans the values of the drawn surface."""
    page = Page(browser, solid_bar / "view.html")
    page("v.select('bar-bending')")
    points, fields = vtu(solid_bar / "bar-bending" / "static.vtu")
    u = np.linalg.norm(fields["displacement"].reshape(-1, 3), axis=1)
    shown = {
        # The colour menu, as a user picks it: the field, the legend's title and its values.
        "displacement": ("elastic displacement [mm]", u * 1e3),
        "von-mises": ("von Mises stress [MPa]", fields["von_mises"] / 1e6),
    }
    nodes = page("Array.from({ length: v.vertexCount(0) }, (_, i) => v.nodeOfVertex(0, i))")
    for choice, (title, expected) in shown.items():
        page.page.select_option("#color", choice)
        name, lo, hi = legend(page)
        assert name == title
        surface = expected[sorted(set(nodes))]
        # The legend's ends, as printed (3 digits): zero and the largest value on the surface.
        assert lo == 0 and hi == pytest.approx(surface.max(), rel=5e-3), (choice, hi, surface.max())
        bar = legend_bar(page)
        for i, n in list(enumerate(nodes))[::37]:
            # The page sums float32 shapes: a few parts in 10^7 of each term, 2e-5 leaves room
            # for the sum's cancellation; near zero the largest value's 1e-6.
            assert page(f"v.value(0, {i})") == pytest.approx(expected[n], rel=2e-5, abs=1e-6 * surface.max())
            x = round((len(bar) - 1) * expected[n] / surface.max())
            colour = srgb(page(f"v.vertexColor(0, {i})"))
            # The bar has 180 pixels and the page's table 256 levels: neighbouring bar pixels
            # differ by up to about 0.02 per channel, plus the legend's 3-digit end and the
            # 8-bit canvas; 0.04 is two pixels' step.
            assert np.abs(colour - bar[x]).max() < 0.04, (choice, n, colour, bar[x])
    page.check_clean()


def test_colour_by_body_follows_the_legend(browser, slider_crank):
    """Coloured by body, every vertex of a body has the colour of its row in the legend, which
    names the bodies in the order of the VTU's `body` field, and no two bodies share one."""
    page = Page(browser, slider_crank / "view.html")
    page.page.select_option("#color", "body")
    rows = page.page.evaluate(
        "() => Array.from(document.querySelectorAll('#legend > div:not(.markers)')).map((r) =>"
        " [r.textContent, getComputedStyle(r.querySelector('span')).backgroundColor])"
    )
    bodies = page("v.bodies()")
    assert [name for name, _ in rows] == bodies
    swatches = []
    for j, (name, css) in enumerate(rows):
        swatch = np.array([float(c) for c in re.findall(r"[0-9.]+", css)[:3]]) / 255
        colours = srgb([page(f"v.vertexColor({j}, {i})") for i in range(page(f"v.vertexCount({j})"))])
        # The swatch is the 8-bit colour; the vertex its float32 linear value encoded back.
        assert np.abs(colours - swatch).max() < 1e-5, name
        swatches.append(swatch)
    assert len({tuple(s) for s in swatches}) == len(bodies)
    _, fields = vtu(pvd(slider_crank / "run-up" / "mechanism.pvd")[0][1])
    assert sorted(set(fields["body"].astype(int))) == list(range(len(bodies)))
    page.check_clean()


def test_the_deformation_scale_factor_enlarges_the_elastic_part_only(browser, solid_bar, slider_crank):
    # A static deflection at 20 times its size: the VTU's displacement times 20.
    page = Page(browser, solid_bar / "view.html")
    page("v.select('bar-bending')")
    page.page.fill("#scale", "20")
    points, fields = vtu(solid_bar / "bar-bending" / "static.vtu")
    u = fields["displacement"].reshape(-1, 3)
    for i in range(0, page("v.vertexCount(0)"), 11):
        n = page(f"v.nodeOfVertex(0, {i})")
        # float32 vertices and shapes: 2e-7 m at scale 1 (the stress test), 20 times here.
        assert np.allclose(page(f"v.vertexPosition(0, {i})"), points[n] + 20 * u[n], rtol=0, atol=2e-6)
    page.check_clean()
    # In a mechanism the rigid motion stays and the elastic part scales: at 0 each rod segment
    # (four beam elements of 0.075 m) is straight and of its length, at 1 it bends.
    page = Page(browser, slider_crank / "view.html")
    page(f"v.setFrame({page('v.frameCount()') - 1})")
    segment = page("v.bodies()").index("r1")

    mesh_nodes = sorted({page(f"v.nodeOfVertex({segment}, {i})") for i in range(page(f"v.vertexCount({segment})"))})
    assert len(mesh_nodes) == 5
    # The rod is drawn as a tube of its section: d = 6 mm, its ring vertices 3 mm from the node
    # (float32 positions near 0.3 m: 1e-7 m).
    ring = [page(f"v.vertexPosition({segment}, {i})") for i in page(f"v.verticesOfNode({segment}, {mesh_nodes[2]})")]
    assert np.allclose(np.linalg.norm(np.array(ring) - np.mean(ring, axis=0), axis=1), 0.003, rtol=0, atol=1e-7)

    def nodes(scale):
        page.page.fill("#scale", str(scale))
        return np.array([page.node_position(segment, n) for n in mesh_nodes])

    straight, bent, far = nodes(0), nodes(1), nodes(3)
    # The segment's ends: its two nodes farthest apart.
    gaps = np.linalg.norm(straight[:, None] - straight[None], axis=2)
    a, b = np.unravel_index(np.argmax(gaps), gaps.shape)
    chord = straight[b] - straight[a]
    # float32 vertices (0.3 m from the origin: 2e-8 m steps) bound the three checks below to
    # about 1e-7 m; the rod's bending at this time is well above 1e-6 m.
    assert np.linalg.norm(chord) == pytest.approx(0.075, rel=1e-6)
    off_chord = lambda p: np.linalg.norm(np.cross(p - p[a], chord), axis=1) / np.linalg.norm(chord)
    assert off_chord(straight).max() < 1e-7
    assert off_chord(bent).max() > 1e-6
    assert np.allclose(far - straight, 3 * (bent - straight), rtol=0, atol=1e-7)
    page.check_clean()


def test_play_pause_and_speed_move_the_time_as_the_controls_say(browser, slider_crank):
    page = Page(browser, slider_crank / "view.html")
    keys = page("v.frameKeys()")
    end = keys[-1]
    play = page.page.locator("#play")
    assert not page("v.playing()") and play.text_content() == "play"
    # The speed menu scales the time one second of playing moves: stepped here by the page's own
    # clock function, so the arithmetic is exact.
    for speed, seconds in [("0.25", 0.02), ("2", 0.004)]:
        page.page.select_option("#speed", speed)
        assert page("v.speed()") == float(speed)
        page("v.setFrame(0)")
        page(f"v.advance({seconds})")
        t = float(speed) * seconds
        assert page("v.clock()") == pytest.approx(t, abs=1e-12)
        k = max(i for i, key in enumerate(keys) if key <= t + 1e-12)
        assert page("v.frame()") == k and int(page.page.locator("#slider").input_value()) == k
        assert f"(frame {k + 1} of {len(keys)})" in page.page.locator("#keyText").text_content()
    # Play runs to the last frame and stops there; at a tenth of real time the 0.03 s of the run
    # take at least 0.3 s, less one frame's step.
    page.page.select_option("#speed", "0.1")
    page("v.setFrame(0)")
    start = page.page.evaluate("() => performance.now()")
    play.click()
    assert play.text_content() == "pause"
    page.page.wait_for_function(f"!{API}.playing()", timeout=20000)
    elapsed = (page.page.evaluate("() => performance.now()") - start) / 1000
    assert page("v.frame()") == len(keys) - 1 and play.text_content() == "play"
    assert elapsed > end / 0.1 - 0.1, elapsed
    # Pause holds the time where it is: play, two frames later pause (clicked in the page, as
    # the run would end before a second click from here under load).
    page("v.setFrame(0)")
    page.page.eval_on_selector(
        "#play", "async (b) => { b.click(); await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))); b.click(); }"
    )
    assert play.text_content() == "play" and not page("v.playing()")
    assert 0 < page("v.clock()") < end
    held = page("v.clock()")
    page.page.wait_for_timeout(300)
    assert page("v.clock()") == held
    page.check_clean()


def test_the_sensor_plots_cursor_follows_the_time(browser, slider_crank):
    """Each sensor's plot has its cursor (a black vertical line) at the time shown, and the
    values beside it are the sensor's CSV row at that time."""
    page = Page(browser, slider_crank / "view.html")
    plots = page.page.locator(".plot")
    names = [re.match(r"sensor (\S+) \(against t \[s\]\)", plots.nth(k).locator(".name").text_content()).group(1) for k in range(plots.count())]
    assert sorted(names) == sorted(p.stem for p in (slider_crank / "run-up").glob("*.csv"))
    keys = page("v.frameKeys()")
    for k in [0, len(keys) // 2, len(keys) - 1]:
        page.page.eval_on_selector("#slider", "(e, k) => { e.value = k; e.dispatchEvent(new Event('input')); }", k)
        t = keys[k]
        for p, name in enumerate(names):
            csv = slider_crank / "run-up" / f"{name}.csv"
            header = csv.read_text().splitlines()[0].split(",")
            table = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
            row = table[np.searchsorted(table[:, 0], t + 1e-12) - 1]
            readout = dict(re.findall(r"\s*([^,=]+?) = ([^,]+)", plots.nth(p).locator("div").nth(1).text_content()))
            assert list(readout) == header[1:], (name, readout)
            # The readout prints 4 significant digits (half a unit: 5e-4 relative) of float32
            # values; values near zero print as a few units of the column's largest.
            for col, value in zip(header[1:], row[1:]):
                assert float(readout[col]) == pytest.approx(value, rel=1e-3, abs=1e-3 * np.abs(table[:, 1:]).max()), (name, col, t)
            # The cursor: the column of the plot's canvas with the most black pixels.
            w, columns = plots.nth(p).locator("canvas").evaluate(
                "(c) => { const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; const n = new Array(c.width).fill(0);"
                " for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 60 && d[i] + d[i + 1] + d[i + 2] < 90) n[(i / 4) % c.width]++;"
                " return [c.width, n]; }"
            )
            x = 4 + (t - table[0, 0]) / (table[-1, 0] - table[0, 0]) * (w - 8)
            # A 1-pixel line at a fractional x covers the two pixel columns around it.
            assert abs(int(np.argmax(columns)) - x) <= 1.5, (name, t, np.argmax(columns), x)
    page.check_clean()


def test_the_markers_sit_on_their_joints_supports_and_point_masses(browser, tmp_path):
    """The built-in slider-crank with a point mass at the rod's middle: each joint's marker on
    its joint, the slider's support on the slider, the mass on its node, as the sensors say."""
    import subprocess

    from conftest import EXAMPLES, cli_path

    study = (EXAMPLES / "slider_crank.toml").read_text()
    study += '\n[[point_masses]]\nname = "tip"\nat = "r1.b"\nmass = 0.001\n'
    study += '\n[[sensors]]\nname = "middle"\ntype = "position"\nof = "r1.b"\n'
    (tmp_path / "sc.toml").write_text(study)
    done = subprocess.run([str(cli_path()), "run", "sc.toml", "--t-end", "0.02"], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    res = tmp_path / "sc-results" / "run-up"
    page = Page(browser, tmp_path / "sc-results" / "view.html")
    kinds = {m["name"]: m["kind"] for m in page("v.markers()")}
    joints = ["weld1", "weld2", "weld3", "crank-pivot", "pin-A", "pin-B"]
    # The ground: the slider's support, and the revolute joint's ground point.
    assert kinds == {**{j: "joint" for j in joints}, "slider.P": "ground", "ground.crank-pivot": "ground", "tip": "mass"}

    def at(sensor, t):
        table = np.loadtxt(res / f"{sensor}.csv", delimiter=",", skiprows=1, ndmin=2)
        row = table[np.argmin(np.abs(table[:, 0] - t))]
        assert row[0] == pytest.approx(t, abs=1e-12)
        return row[1:]

    series = pvd(res / "mechanism.pvd")
    for k in [0, len(series) // 2, len(series) - 1]:
        t, file = series[k]
        page(f"v.setFrame({k})")
        drawn = {m["name"]: np.array(m["position"]) for m in page("v.markers()")}
        theta = at("crank-angle", t)[0]
        expected = {
            "crank-pivot": np.zeros(3),
            "ground.crank-pivot": np.zeros(3),
            "pin-A": 0.15 * np.array([np.cos(theta), np.sin(theta), 0.0]),
            "pin-B": at("slider", t),
            "slider.P": at("slider", t),
            "tip": at("middle", t),
        }
        # float64 on both sides (the page's frames and the sensors' CSV of the same node
        # positions, each printed to 17 digits): 1e-9 m only allows for the crank's
        # cos/sin of the printed angle.
        for name, x in expected.items():
            assert np.allclose(drawn[name], x, rtol=0, atol=1e-9), (name, t, drawn[name], x)
        # The welds join rod segments: each sits on a node of the VTU's deformed rod.
        points, fields = vtu(file)
        where = points + fields["displacement"].reshape(-1, 3)
        for name in ["weld1", "weld2", "weld3"]:
            assert np.linalg.norm(where - drawn[name], axis=1).min() < 1e-9, (name, t)
    page.check_drawn()
    page.check_clean()


def test_turn_pan_zoom_and_the_views_along_the_axes(browser, solid_bar):
    """The mouse and the view buttons, seen in the canvas's pixels: the bar's outline along each
    axis has the VTU's proportions; a wheel zooms by its factor; a shift-drag carries the
    drawing with the pointer; a drag turns it, and the opposite drag turns it back; fit brings
    the whole model back into view."""
    from io import BytesIO

    image = pytest.importorskip("matplotlib.image")
    page = Page(browser, solid_bar / "view.html")
    page("v.select('bar-bending')")
    # The legend and the value under the pointer lie over the canvas: hidden, the pixels are the drawing's.
    page.page.add_style_tag(content="#legend, #probe { visibility: hidden !important; }")
    canvas = page.page.locator("#view")
    box = canvas.bounding_box()
    centre = (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)

    def drawn():
        pixels = image.imread(BytesIO(canvas.screenshot()))[..., :3]
        return np.abs(pixels - pixels[0, 0]).sum(axis=-1) > 0.05

    def extent(mask):
        ys, xs = np.nonzero(mask)
        return np.ptp(xs) + 1, np.ptp(ys) + 1

    def centroid(mask):
        ys, xs = np.nonzero(mask)
        return np.array([xs.mean(), ys.mean()])

    points, _ = vtu(solid_bar / "bar-bending" / "static.vtu")
    size = np.ptp(points, axis=0)
    # Along z the screen shows x across and y up, along x the y-z cross-section (perspective:
    # the near face looks larger, so a tenth is allowed).
    for view, (across, up) in {"z": (0, 1), "x": (2, 1), "y": (0, 2)}.items():
        page.page.click(f"#views button[data-view='{view}']")
        w, h = extent(drawn())
        assert w / h == pytest.approx(size[across] / size[up], rel=0.1), (view, w, h, size)
    page.page.click("#views button[data-view='iso']")
    before = drawn()
    # The wheel: the distance times exp(deltaY / 1000), the drawing's size divided by it.
    page.page.mouse.move(*centre)
    page.page.mouse.wheel(0, 300)
    page.page.wait_for_timeout(100)
    zoomed = drawn()
    grown = np.hypot(*extent(zoomed)) / np.hypot(*extent(before))
    assert grown == pytest.approx(math.exp(-0.3), rel=0.1), grown
    # (Smaller, so that nothing leaves the canvas below.)
    # Shift-drag: the drawing follows the pointer.
    page.page.keyboard.down("Shift")
    page.page.mouse.down()
    page.page.mouse.move(centre[0] + 60, centre[1] + 30, steps=5)
    page.page.mouse.up()
    page.page.keyboard.up("Shift")
    panned = drawn()
    # Exact for a point at the target's depth; the bar's near and far ends move a little more
    # and less under the perspective, so the centroid within 6 of 67 pixels.
    assert np.allclose(centroid(panned) - centroid(zoomed), [60, 30], atol=6), centroid(panned) - centroid(zoomed)
    # A drag turns the drawing; the opposite drag turns it back.
    page.page.mouse.move(*centre)
    page.page.mouse.down()
    page.page.mouse.move(centre[0] + 80, centre[1], steps=5)
    page.page.mouse.up()
    turned = drawn()
    assert (turned != panned).mean() > 0.01
    page.page.mouse.down()
    page.page.mouse.move(*centre, steps=5)
    page.page.mouse.up()
    back = drawn()
    # The same angles again: the same picture but for edge pixels, where the angle's five
    # steps there and back round differently.
    assert (back != panned).mean() < 0.002
    # Fit: the whole bar in view again, at the size it had.
    page.page.click("#views button[data-view='fit']")
    fitted = drawn()
    assert np.hypot(*extent(fitted)) == pytest.approx(np.hypot(*extent(back)) / math.exp(-0.3), rel=0.1)
    page.check_clean()


def column_study(rest: str) -> str:
    """examples/cantilever.toml's beam as a column, 2 m along x, clamped at its root and pushed
    at its tip by 345 N (about a tenth of its Euler load), then `rest`."""
    from conftest import EXAMPLES

    text = (EXAMPLES / "cantilever.toml").read_text()
    return text[: text.index("[[analyses]]")] + (
        '[[bodies]]\nname = "column"\npart = "beam"\n\n'
        '[[joints]]\nname = "base"\ntype = "fixed"\nbetween = ["ground", "column.root"]\n\n'
        '[[loads]]\nname = "push"\ntype = "point"\nat = "column.tip"\nforce = [-345.0, 0.0, 0.0]\n\n'
    ) + rest


def test_buckling_modes_animate_with_their_load_factors(browser, tmp_path):
    """A clamped steel column pushed at its tip: each buckling mode is labelled with the load
    factor of load_factors.csv, and drawn as the shape of its VTU file, about the loaded
    column and scaled."""
    import subprocess

    from conftest import cli_path

    (tmp_path / "column.toml").write_text(column_study('[[analyses]]\ntype = "buckling"\nname = "buckling"\nmodes = 2\n'))
    done = subprocess.run([str(cli_path()), "run", "column.toml"], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    res = tmp_path / "column-results" / "buckling"
    page = Page(browser, tmp_path / "column-results" / "view.html")
    assert page("v.analyses()") == ["buckling"]
    factors = np.loadtxt(res / "load_factors.csv", delimiter=",", skiprows=1, usecols=1, ndmin=1)
    modes = page("v.modes()")
    assert [m["label"] for m in modes] == [f"mode {k + 1}: load factor {f:.6f}" for k, f in enumerate(factors)]
    page("v.pause()")
    nodes = sorted({page(f"v.nodeOfVertex(0, {i})") for i in range(page("v.vertexCount(0)"))})
    for k in range(len(modes)):
        page(f"v.setMode({k})")
        points, fields = vtu(res / f"mode_{k + 1:03}.vtu")
        shape = fields["displacement"].reshape(-1, 3)[nodes]
        page("v.setPhase(0)")
        rest = np.array([page.node_position(0, n) for n in nodes])
        page(f"v.setPhase({math.pi / 2})")
        drawn = np.array([page.node_position(0, n) for n in nodes]) - rest
        ratio = np.sum(drawn * shape) / np.sum(shape**2)
        assert ratio != 0
        # The mode's pose is the mode at a finite amplitude (a frame turned by 0.05 rad):
        # second-order terms of a few parts in 10^6 of the shape, float32 vertices below that.
        assert np.allclose(drawn, ratio * shape, rtol=0, atol=1e-4 * np.abs(drawn).max()), k
        # Sideways: the column (along x) bends, its tip moving across it (the axial part is of
        # the second order, under 1 % here) by a tenth of the model's half-diagonal (1.0 m for
        # the 2 m column; 5 % leaves room for the tube's width in the diagonal).
        tip = np.argmax(points[nodes, 0])
        assert abs(drawn[tip, 0]) < 0.05 * np.linalg.norm(drawn[tip])
        assert np.linalg.norm(drawn[tip]) == pytest.approx(0.1 * 2.0 / 2, rel=0.05)
        # The scale factor enlarges the drawn mode as the linear displacement field it is: the
        # clamped root stays where it is at any scale.
        page("v.setScale(10)")
        ten = np.array([page.node_position(0, n) for n in nodes]) - rest
        # Linear in the scale to round-off (float32 positions, 1e-7 m of 2 m); the root moves
        # only by the mode pose's own second-order drift, 1e-6 of the tip's motion.
        assert np.allclose(ten, 10 * drawn, rtol=0, atol=1e-5 * np.abs(drawn).max()), k
        root = np.argmin(points[nodes, 0])
        assert np.linalg.norm(ten[root]) < 1e-5 * np.linalg.norm(ten[tip]), (k, ten[root])
        page("v.setScale(1)")
    assert page.page.locator("#mode option").nth(0).text_content() == modes[0]["label"]
    page.check_drawn()
    page.check_clean()


def test_the_model_before_it_runs_shows_interfaces_supports_and_loads(browser, tmp_path):
    """`flexmbs view STUDY.toml`: the page of a clamped column before it runs, its interfaces,
    the clamp and its two loads (one at an interface node, one at a load point inside the
    body) as markers where the study puts them, the loads as arrows along their forces."""
    import subprocess

    from conftest import cli_path

    study = column_study(
        '[[loads]]\nname = "side"\ntype = "point"\nat = "column.mid"\nforce = [0.0, 0.0, -10.0]\n\n'
        '[[analyses]]\ntype = "equilibrium"\nname = "eq"\n'
    ).replace("modes = 4\n", 'modes = 4\nload_points = [{ name = "mid", node_at = [1.0, 0.0, 0.0] }]\n')
    (tmp_path / "column.toml").write_text(study)
    done = subprocess.run([str(cli_path()), "view", "column.toml"], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "column-model.html"
    page = Page(browser, tmp_path / "column-model.html")
    assert page("v.bodies()") == ["column"] and page("v.frameCount()") == 1
    # One frame: nothing to play, so no play button, speed or time slider.
    assert not page.page.locator("#play").is_visible() and not page.page.locator("#slider").is_visible()
    markers = page("v.markers()")
    drawn = {m["name"]: m for m in markers if m["kind"] != "ground"}
    expected = {
        "column.root": ("interface", [0, 0, 0], None),
        "column.tip": ("interface", [2, 0, 0], None),
        "push": ("load", [2, 0, 0], [-345, 0, 0]),
        "side": ("load", [1, 0, 0], [0, 0, -10]),
    }
    for name, (kind, at, direction) in expected.items():
        m = drawn[name]
        # The column before it runs: the study's own coordinates, in float64 throughout.
        assert m["kind"] == kind and np.allclose(m["position"], at, atol=1e-12), m
        assert (m["direction"] is None) == (direction is None) and (direction is None or np.allclose(m["direction"], direction)), m
    # The clamp: a support at the root.
    assert [(m["name"], m["position"]) for m in markers if m["kind"] == "ground"] == [("column.root", [0, 0, 0])]
    key = page.page.locator("#legend .markers").text_content()
    assert all(k in key for k in ["interface", "ground, support", "load"]), key
    page.check_drawn()
    page.screenshot("model")
    page.check_clean()
