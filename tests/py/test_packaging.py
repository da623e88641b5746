"""Packaging: one version everywhere, a wheel that carries libdem inside and imports away from
the checkout, the `pydem` command, and a C library that builds and installs without Python
(portable flags, versioned soname, no rpath) and links from its pkg-config file."""
import json
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

import pydem

ROOT = Path(__file__).resolve().parents[2]


def test_one_version_in_pyproject_package_and_headers():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    header = re.search(r'#define DEM_VERSION_STRING "(.*)"', (ROOT / "include/dem/base.h").read_text()).group(1)
    assert project["version"] == pydem.__version__ == header == pydem.LIBDEM_VERSION
    assert project["license"] == "MIT" and (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert "torch==2.13.0" in project["optional-dependencies"]["nn"]
    assert not any(d.startswith("torch") for d in project["dependencies"]), "torch must stay an extra"


def test_the_wheel_lists_every_python_package():
    """A package folder missing from pyproject's list would be left out of `pip install .`."""
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for top in ("pydem", "nn") for p in (ROOT / top).rglob("__init__.py")}
    assert found == listed


def test_pydem_version_command():
    out = subprocess.run([sys.executable, "-m", "pydem", "--version"], capture_output=True, text=True, check=True).stdout
    assert out.strip() == f"pydem {pydem.__version__} (libdem {pydem.LIBDEM_VERSION})"


def test_plain_make_needs_no_python():
    """`make` (all) and `make install` must not call the virtual environment's Python."""
    for target in ("all", "install"):
        dry = subprocess.run(["make", "-n", "-B", target, "PYTHON=/no/such/python", "PREFIX=/tmp/never"], cwd=ROOT,
                             capture_output=True, text=True)
        assert dry.returncode == 0, dry.stderr
        assert "/no/such/python" not in dry.stdout, f"make {target} runs Python"


def test_install_is_portable_versioned_and_links(tmp_path):
    dest = tmp_path / "root"
    log = subprocess.run(["make", "-j2", "install", f"DESTDIR={dest}", "PREFIX=/opt/dem"], cwd=ROOT,
                         capture_output=True, text=True)
    assert log.returncode == 0, log.stdout[-3000:] + log.stderr[-3000:]
    compiles = [line for line in log.stdout.splitlines() if " -c libdem/" in line]
    assert all("-march" not in line for line in compiles), "the installed library must not assume this CPU"
    lib = dest / "opt/dem/lib"
    version = pydem.LIBDEM_VERSION
    soname = f"libdem.so.{version.split('.')[0]}"
    assert (lib / f"libdem.so.{version}").is_file()
    assert (lib / soname).resolve() == (lib / f"libdem.so.{version}").resolve()
    assert (lib / "libdem.so").resolve() == (lib / f"libdem.so.{version}").resolve()
    if shutil.which("readelf"):
        dyn = subprocess.run(["readelf", "-d", str(lib / f"libdem.so.{version}")], capture_output=True, text=True).stdout
        assert f"Library soname: [{soname}]" in dyn
        assert "RPATH" not in dyn and "RUNPATH" not in dyn
    # docs/libdem.md's C example against the installed headers and library, through dem.pc
    example = tmp_path / "example.c"
    doc = (ROOT / "docs/libdem.md").read_text()
    example.write_text(re.search(r"```c libdem-example\n(.*?)```", doc, re.S).group(1))
    pc = (lib / "pkgconfig/dem.pc").read_text().replace("prefix=/opt/dem", f"prefix={dest}/opt/dem")
    (tmp_path / "pc").mkdir()
    (tmp_path / "pc/dem.pc").write_text(pc)
    env = {"PKG_CONFIG_PATH": str(tmp_path / "pc"), "PATH": "/usr/bin:/bin"}
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "dem"], env=env, capture_output=True, text=True,
                           check=True).stdout.split()
    deps = subprocess.run(["pkg-config", "--libs", "hdf5-serial", "libpng"], capture_output=True, text=True).stdout.split()
    exe = tmp_path / "example"
    subprocess.run(["gcc", "-std=c99", str(example), "-o", str(exe), *flags, *deps], check=True)
    run = subprocess.run([str(exe)], cwd=ROOT, env={"LD_LIBRARY_PATH": str(lib)}, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    ldd = subprocess.run(["ldd", str(exe)], env={"LD_LIBRARY_PATH": str(lib)}, capture_output=True, text=True).stdout
    assert f"{soname} => {lib}" in ldd


@pytest.mark.slow
@pytest.mark.skipif(not shutil.which("gcc"), reason="needs a C compiler")
def test_wheel_builds_libdem_from_sources_and_runs_outside_the_checkout(tmp_path):
    wheels = tmp_path / "wheels"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", "-w",
                            str(wheels), str(ROOT)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr[-3000:]
    wheel = next(wheels.glob("pydem-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert any(re.match(r"pydem/_libdem\..*so$", n) for n in names) and "nn/mlp.py" in names
    assert any(n.endswith("entry_points.txt") for n in names)
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), str(wheel)],
                   check=True, capture_output=True)
    code = ("import pydem, numpy as np\n"
            "d = pydem.Domain(lo=(0, 0, 0), hi=(0.1, 0.1, 0.1))\n"
            "glass = d.add_material(youngs_modulus=5e6)\n"
            "d.add_particles(np.array([[0.05, 0.05, 0.05]]), 0.005, glass)\n"
            "d.step(10)\n"
            "assert d.positions[0, 2] < 0.05\n"
            "print(pydem.__file__)\n")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env={"PYTHONPATH": str(target)},
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.strip().startswith(str(target)), run.stdout
    # the main job from a directory outside the checkout, on the stores and cached nets the wheel carries
    assert any(n.startswith("pydem/data/campaigns/") and n.endswith(".h5") for n in names)
    meas = target / "pydem/data/measurements/synthetic_cohesive.csv"
    job = subprocess.run([sys.executable, "-m", "pydem", "diagnose", str(meas), "--material", "synthetic_cohesive",
                          "--out", "diag"], cwd=tmp_path, env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True)
    assert job.returncode == 0, job.stderr[-3000:]
    report = json.loads((tmp_path / "diag/diagnosis.json").read_text())
    assert report["effect"] == "cohesion_sjkr"
    assert all(s["path"].startswith(str(target)) for s in report["context"]["stores"].values())


@pytest.mark.parametrize("call, compiles", [
    ("dem_mesh_wall_force(d, mesh, NULL, f, NULL)", True),
    ("dem_mesh_wall_force(d, plane, NULL, f, NULL)", False),   # a plane wall where a mesh wall goes
    ("dem_plane_wall_force(d, plane, f)", True),
    ("dem_pair_set(d, mat, mat, NULL)", True),
    ("dem_pair_set(d, mat, mesh, NULL)", False),               # a wall where a material goes
    ("dem_pair_set(d, 0, 1, NULL)", False),                    # bare ints are not handles
])
def test_typed_handles_do_not_mix(tmp_path, call, compiles):
    """Materials, plane walls and mesh walls are distinct handle types in the C API: misuse is a
    compile error (gcc: incompatible type), right use compiles (docs/libdem.md, "Handles")."""
    src = tmp_path / "h.c"
    src.write_text('#include "dem/dem.h"\nvoid f_(dem_domain *d, dem_material mat, dem_plane_wall plane, '
                   f'dem_mesh_wall mesh) {{ double f[3]; (void){call}; }}\n')
    r = subprocess.run(["cc", "-std=c99", "-fsyntax-only", "-Werror", f"-I{ROOT / 'include'}", str(src)],
                       capture_output=True, text=True)
    assert (r.returncode == 0) == compiles, r.stderr
    if not compiles:
        assert "incompatible type" in r.stderr
