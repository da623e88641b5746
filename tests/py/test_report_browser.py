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


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    assert exe, "chromium is missing: run scripts/setup.sh"
    return exe


def screenshot(page: Path, png: Path, width: int = 1200) -> str:
    r = subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        f"--window-size={width},3200", "--enable-logging=stderr", "--v=0", f"--screenshot={png}",
                        page.as_uri()], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and png.exists(), r.stderr[-2000:]
    return r.stderr


def page_width(page: Path, width: int, tmp: Path) -> int:
    """The laid-out page's scroll width in a window `width` pixels wide: a copy of the page whose
    script writes it into the DOM, which headless Chromium dumps after layout."""
    probe = tmp / f"probe_{width}.html"
    probe.write_text(page.read_text().replace("</body>", "<script>document.body.setAttribute('data-width', "
                                                         "document.documentElement.scrollWidth)</script></body>"))
    r = subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", f"--window-size={width},2000",
                        "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    import re
    return int(re.search(r'data-width="(\d+)"', r.stdout).group(1))


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
    # matplotlib's C0 blue (the base or calibrated model) and C3 red (the model with the effect, the
    # best estimate's star): drawn only if the images loaded
    assert pixels_near(img, (31, 119, 180)) > 500
    assert pixels_near(img, (214, 39, 40)) > 20
    # at a desktop's and at a phone's width, nothing runs off the side: wide tables scroll in their box
    for width in (1200, 500):  # 500: headless Chromium's narrowest window
        assert page_width(out / "report.html", width, tmp_path) <= width
    # the verdict opens both reports, before any plot
    page = (out / "report.html").read_text()
    assert page.index("class='verdict'") < page.index("<img")
    # every statistic explained in plain words, and what made the report
    for heading in ("What the numbers mean", "Provenance"):
        assert f"<h2>{heading}</h2>" in page
    assert ("LR (likelihood ratio)" in page) == (command == "diagnose") and "git_commit" in page
