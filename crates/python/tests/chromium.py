"""The headless Chromium that the browser tests and benchmarks/scripts/viewer_fps.py drive:
the system's (Debian's `chromium` package at /usr/bin/chromium, or $FLEXMBS_CHROMIUM), never a
downloaded one, with WebGL on the CPU (SwiftShader) and no network of its own."""

import os
from pathlib import Path

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
MISSING = f"no Chromium at {CHROMIUM} (apt-get install chromium, or set FLEXMBS_CHROMIUM)"
