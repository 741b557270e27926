#!/usr/bin/env python3
"""The results page (`view.html`) of a large solid body: its size against the VTU series of
the same run, its load time and its frames per second while playing, in headless Chromium.

    python3 benchmarks/scripts/viewer_fps.py [--study FILE] [--seconds 5] [--keep DIR]
    python3 benchmarks/scripts/viewer_fps.py --results DIR    # measure an existing run

Runs `flexmbs run` (the program from FLEXMBS_CLI, else target/release/flexmbs) on
benchmarks/studies/viewer_solid_bar.toml (a 29 524-node hex8 bar, 6 modes, 1000 frames, a VTU
frame every step: the series takes about 10 GB) in a temporary folder, deleted at the end
unless `--keep DIR` names where to run. Then, with Playwright driving the system's Chromium
(/usr/bin/chromium or FLEXMBS_CHROMIUM) launched as the browser tests launch it
(crates/python/tests/chromium.py):

- load: from `page.goto` to the page's `load` event, and to its first rendered frame
  (`flexmbsViewer.renders()` > 0);
- playing: `flexmbsViewer.play()` from the first frame, restarted when it reaches the end,
  for `--seconds`; frames per second = renders (`flexmbsViewer.renders()`) per wall second;
- still: one frame rendered again every animation frame (`flexmbsViewer.setView`), no
  update of the body: what the rendering alone allows, to set the playing figure against;
- stepping: `flexmbsViewer.setFrame(k)` over every frame (the update and the render call
  of each frame, JavaScript side), its mean milliseconds per frame.

Chromium here renders WebGL with SwiftShader (on the CPU, no GPU): the frames per second are
a lower bound of what a desktop browser with a GPU shows. Needs `pip install playwright`
(PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1: the system's Chromium is used).
"""

import argparse
import gzip
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "crates" / "python" / "tests"))
from chromium import ARGS, CHROMIUM, MISSING  # noqa: E402 (the tests' browser, launched alike)

API = "window.flexmbsViewer"


def cpu_name():
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def run_study(study: Path, folder: Path) -> Path:
    cli = os.environ.get("FLEXMBS_CLI") or str(ROOT / "target" / "release" / "flexmbs")
    if not Path(cli).is_file():
        sys.exit(f"no flexmbs program at {cli} (cargo build --release -p flexmbs, or set FLEXMBS_CLI)")
    folder.mkdir(parents=True, exist_ok=True)
    local = folder / study.name
    shutil.copy(study, local)
    t0 = time.perf_counter()
    subprocess.run([cli, "run", local.name], cwd=folder, check=True)
    print(f"flexmbs run: {time.perf_counter() - t0:.1f} s wall ({cli})")
    return folder / f"{study.stem}-results"


def sizes(results: Path):
    page = results / "view.html"
    vtu = [p for p in results.rglob("*") if p.suffix in (".vtu", ".pvd")]
    nvtu = sum(1 for p in vtu if p.suffix == ".vtu")
    vtu_bytes = sum(p.stat().st_size for p in vtu)
    page_bytes = page.stat().st_size
    page_gz = len(gzip.compress(page.read_bytes(), 6))
    return page, page_bytes, page_gz, nvtu, vtu_bytes


def measure(page_path: Path, seconds: float, chromium: Path):
    import playwright.sync_api as playwright

    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(chromium), headless=True, args=ARGS)
        page = browser.new_page(viewport={"width": 900, "height": 520})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        t0 = time.perf_counter()
        page.goto(page_path.as_uri(), wait_until="load", timeout=300_000)
        t_load = time.perf_counter() - t0
        page.wait_for_function(f"{API} && {API}.ready && {API}.renders() > 0", timeout=300_000)
        t_first = time.perf_counter() - t0
        if errors:
            sys.exit(f"the page reported errors: {errors}")
        info = page.evaluate(
            f"() => ({{ frames: {API}.frameCount(), bodies: {API}.bodies(),"
            f" vertices: {API}.bodies().map((b) => {API}.vertexCount(b)),"
            f" rendering: {API}.rendering() }})"
        )
        playing = page.evaluate(
            """async (seconds) => {
                const v = window.flexmbsViewer;
                const frame = () => new Promise((r) => requestAnimationFrame(r));
                v.setFrame(0); v.play();
                await frame();
                const r0 = v.renders(), t0 = performance.now();
                let restarts = 0;
                while (performance.now() - t0 < 1000 * seconds) {
                    await frame();
                    if (!v.playing()) { v.setFrame(0); v.play(); restarts++; }
                }
                const renders = v.renders() - r0 - restarts, t = (performance.now() - t0) / 1000;
                v.pause();
                return { renders, seconds: t, restarts };
            }""",
            seconds,
        )
        # The same frame drawn again and again (setView renders without updating the body):
        # what the rendering alone allows.
        still = page.evaluate(
            """async (seconds) => {
                const v = window.flexmbsViewer;
                const frame = () => new Promise((r) => requestAnimationFrame(r));
                v.setFrame(Math.floor(v.frameCount() / 2));
                await frame();
                const r0 = v.renders(), t0 = performance.now();
                while (performance.now() - t0 < 1000 * seconds) { v.setView('iso'); await frame(); }
                return { renders: v.renders() - r0, seconds: (performance.now() - t0) / 1000 };
            }""",
            seconds,
        )
        stepping = page.evaluate(
            """() => {
                const v = window.flexmbsViewer, n = v.frameCount();
                const t0 = performance.now();
                for (let k = 0; k < n; k++) v.setFrame(k);
                return { frames: n, ms: (performance.now() - t0) / n };
            }"""
        )
        browser.close()
    return t_load, t_first, info, playing, still, stepping


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--study", type=Path, default=ROOT / "benchmarks" / "studies" / "viewer_solid_bar.toml")
    ap.add_argument("--seconds", type=float, default=5.0, help="how long to play (wall seconds)")
    ap.add_argument("--keep", type=Path, help="run in this folder and keep the results (about 10 GB)")
    ap.add_argument("--results", type=Path, help="measure this existing results folder instead of running")
    args = ap.parse_args()
    chromium = CHROMIUM
    if not chromium.is_file():
        sys.exit(MISSING)

    tmp = None
    if args.results:
        results = args.results
    else:
        folder = args.keep or Path(tempfile.mkdtemp(prefix="viewer-fps-"))
        tmp = None if args.keep else folder
        results = run_study(args.study.resolve(), folder)
    try:
        page, page_bytes, page_gz, nvtu, vtu_bytes = sizes(results)
        t_load, t_first, info, playing, still, stepping = measure(page, args.seconds, chromium)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)

    fps = playing["renders"] / playing["seconds"]
    load = os.getloadavg()
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores, load {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
    r = info["rendering"]
    print(f"WebGL renderer: {r['webgl']} ({'multisampled' if r['antialias'] else 'without multisampling'})")
    if r["software"]:
        print("  Chromium renders WebGL in software here (on the CPU, no GPU), and the page then draws")
        print("  without multisampling: the frame rates below are those of this CPU; a browser with a GPU")
        print("  draws the same page multisampled.")
    print(f"bodies: {', '.join(f'{b} ({n} surface vertices)' for b, n in zip(info['bodies'], info['vertices']))}; {info['frames']} frames")
    print(f"page:       {page_bytes / 1e6:9.2f} MB ({page_gz / 1e6:.2f} MB gzipped)  {page}")
    print(f"VTU series: {vtu_bytes / 1e6:9.2f} MB in {nvtu} .vtu files and the .pvd ({vtu_bytes / page_bytes:.0f}x the page)")
    print(f"load:       {t_load:.2f} s to the load event, {t_first:.2f} s to the first rendered frame")
    print(f"playing:    {fps:.1f} frames per second ({playing['renders']} renders in {playing['seconds']:.1f} s, {playing['restarts']} restarts)")
    print(f"still:      {still['renders'] / still['seconds']:.1f} frames per second drawing one frame again and again (rendering alone)")
    print(f"stepping:   {stepping['ms']:.1f} ms per frame for setFrame over all {stepping['frames']} frames (update + render call)")


if __name__ == "__main__":
    main()
