"""Every `pydem` command and campaign TOML shown in README.md and docs/ is checked against the
code, so the documentation cannot drift from it: each command line parses with today's flags;
rig commands validate their configuration (`--list`, no run); campaign specs (files and TOML
blocks) load and validate every key at both range ends; measurement files and stores named in a
command load; `pydem diagnose` and `campaign status` examples run. (A documented key that the code
refuses, as `effects.cohesion_sjkr.energy_density` once was, fails here.)"""
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from pydem.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def blocks(path: Path, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", path.read_text(), flags=re.S)


def commands() -> list[tuple[str, list[str]]]:
    out = []
    for doc in DOCS:
        for block in blocks(doc, "sh"):
            text = re.sub(r"\\\n\s*", " ", block)  # join continued lines
            for line in text.splitlines():
                line = line.split("  #")[0].strip().replace("$R/", "")  # the README tour's checkout variable
                if line.startswith(".venv/bin/pydem "):
                    out.append((f"{doc.name}: {line[:70]}", shlex.split(line)[1:]))
    return out


COMMANDS = commands()


def in_the_tour(argv: list[str]) -> bool:
    """A command of the README tour (its test runs the tour as written), by its measurement file
    and material."""
    tour = next(b for b in blocks(ROOT / "README.md", "sh") if b.startswith("R=$PWD"))
    return f"$R/{argv[1]} --material {argv[3]}" in tour


def test_the_docs_have_examples():
    assert len(COMMANDS) >= 15


@pytest.mark.parametrize("argv", [c[1] for c in COMMANDS], ids=[c[0] for c in COMMANDS])
def test_documented_command(argv, tmp_path):
    args = build_parser().parse_args(argv)  # flags and choices as documented
    cmd = argv[0]
    if cmd == "rig":
        rest, skip = [], False
        for a in argv[2:]:  # without the output flags and their values: --list only validates
            if skip or a in ("--out", "--frames", "--vtk"):
                skip = not skip
                continue
            rest.append(a)
        r = subprocess.run([sys.executable, "-m", "pydem", "rig", argv[1], "--list", *rest], cwd=ROOT,
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
    elif cmd == "campaign" and args.action == "run" and args.spec:
        from pydem.campaign import CampaignSpec
        spec = ROOT / args.spec
        if spec.exists():
            CampaignSpec.from_toml(spec)
    elif cmd == "campaign" and args.action in ("status", "export") and (ROOT / args.store).exists():
        from pydem.campaign import Campaign
        Campaign.open(ROOT / args.store)
    elif cmd in ("calibrate", "compare", "diagnose"):
        from pydem.measurements import load
        load(ROOT / args.measurements, args.material)
        for store in getattr(args, "stores", None) or []:
            from pydem.campaign import Campaign
            Campaign.open(ROOT / store)
        if cmd in ("diagnose", "calibrate") and not in_the_tour(argv):  # the tour's own test runs those
            keep = [a for i, a in enumerate(argv) if a != "--out" and (i == 0 or argv[i - 1] != "--out")]
            r = subprocess.run([sys.executable, "-m", "pydem", *keep, "--out", str(tmp_path / "d")], cwd=ROOT,
                               capture_output=True, text=True, timeout=300)
            assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("doc", [d for d in DOCS if blocks(d, "toml")], ids=lambda d: d.name)
def test_documented_campaign_toml(doc, tmp_path):
    from pydem.campaign import CampaignSpec
    for k, block in enumerate(blocks(doc, "toml")):
        f = tmp_path / f"block{k}.toml"
        f.write_text(block)
        CampaignSpec.from_toml(f)  # every key resolves and both range ends are allowed


@pytest.mark.slow
def test_readme_tour_runs_anywhere_and_leaves_the_checkout_clean(tmp_path):
    """The README's tour, run as written by a shell in a directory outside the checkout: every
    command exits 0, its outputs land there, and `git status` of the checkout is as before."""
    tour = next(b for b in blocks(ROOT / "README.md", "sh") if b.startswith("R=$PWD"))
    # (tracked and untracked files; ignored ones such as build/ may change under other test workers)
    before = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True).stdout
    work = tmp_path / "elsewhere"
    work.mkdir()
    script = tour.replace('R=$PWD; cd "$(mktemp -d)"', f'R={ROOT}; cd {work}')
    r = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    for out in ("aor.json", "rs.json", "locus.png", "cal/report.html", "cal/material_card.liggghts", "diag/report.html"):
        assert (work / out).exists(), out
    after = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True).stdout
    assert after == before


def test_readme_python_blocks_run(tmp_path):
    """The README's Python examples run as written (in a fresh directory)."""
    for k, block in enumerate(blocks(ROOT / "README.md", "python")):
        f = tmp_path / f"example{k}.py"
        f.write_text(block)
        r = subprocess.run([sys.executable, str(f)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr[-2000:]
