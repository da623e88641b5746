"""The HTML reports in a real browser: headless Chromium (Debian's package, installed by
scripts/setup.sh) renders `pydem calibrate`'s and `pydem diagnose`'s report.html without a
console error, and the screenshot shows the embedded plots (their data and markers drawn in
matplotlib's colours), i.e. the images loaded from the self-contained page."""
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
MEAS = ROOT / "data/measurements/synthetic_cohesive.csv"


def screenshot(page: Path, png: Path) -> str:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    assert chromium, "chromium is missing: run scripts/setup.sh"
    r = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        "--window-size=1200,3200", "--enable-logging=stderr", "--v=0", f"--screenshot={png}",
                        page.as_uri()], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and png.exists(), r.stderr[-2000:]
    return r.stderr


def pixels_near(img: np.ndarray, rgb, tol: float = 0.06) -> int:
    return int(np.sum(np.all(np.abs(img[:, :, :3] - np.array(rgb) / 255.0) < tol, axis=2)))


@pytest.mark.parametrize("command", ["calibrate", "diagnose"])
def test_report_renders_with_its_images(command, tmp_path):
    from matplotlib.image import imread
    out = tmp_path / command
    extra = ["--samples", "16384"] if command == "calibrate" else []
    r = subprocess.run([sys.executable, "-m", "pydem", command, str(MEAS), "--material", "synthetic_cohesive",
                        "--out", str(out), *extra], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    log = screenshot(out / "report.html", tmp_path / "shot.png")
    for bad in ("Uncaught", "CONSOLE", "Not allowed to load", "net::ERR"):
        assert bad not in log, log[-2000:]
    img = imread(tmp_path / "shot.png")
    assert img.shape[0] >= 3000 and img.shape[1] == 1200
    # matplotlib's C0 blue (measured points, error bars) and C3 red: drawn only if the images loaded
    assert pixels_near(img, (31, 119, 180)) > 500
    assert pixels_near(img, (214, 39, 40)) > 20
