"""Builds pydem._libdem: cffi in out-of-line API mode over the public headers, with libdem
inside the extension, so the package needs no library path. Two routes, one cdef:

- `pip install .` (pyproject.toml, setup.py: cffi_modules) uses `ffibuilder`: libdem compiled
  from libdem/*.c with portable flags (no -march: a wheel runs on any x86-64);
- `make pydem` (and so `make test`, `make demo`) runs this file: the extension is linked against
  build/libdem.a, compiled in parallel by make with this machine's flags, and placed in pydem/.

The cdef is generated from include/dem/*.h (comments, preprocessor lines, C++ guards and the
DEM_API export macro removed), so the binding cannot drift from the headers.
"""
import re
import os
import shutil
import subprocess
import sys
from pathlib import Path

import cffi

ROOT = Path(__file__).resolve().parent.parent
INCLUDE = ROOT / "include" / "dem"
HEADERS = ["base.h", "types.h", "mesh.h", "stress.h", "io.h", "mlp.h", "dem.h"]  # dependency order
KEEP_DEFINES = re.compile(r"#define\s+(DEM_VERSION_(?:MAJOR|MINOR|PATCH))\s+(\d+)\s*$")


def header_declarations(text: str) -> str:
    """The C declarations of one public header, in a form cffi's cdef accepts."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    out, skip_cpp = [], False
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("#"):
            if s.startswith("#ifdef __cplusplus"):
                skip_cpp = True
            elif s.startswith("#endif"):
                skip_cpp = False
            m = KEEP_DEFINES.match(s)
            if m:
                out.append(f"#define {m.group(1)} {m.group(2)}")
            continue
        if skip_cpp:
            continue
        out.append(line.replace("DEM_API ", ""))
    return "\n".join(out)


def cdef_source() -> str:
    return "\n".join(header_declarations((INCLUDE / h).read_text()) for h in HEADERS)


def pkg_config(*args: str) -> list[str]:
    try:
        return subprocess.run(["pkg-config", *args, "hdf5-serial", "libpng"], check=True, capture_output=True,
                              text=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        return ["-lhdf5", "-lpng"] if "--libs" in args else []


# libdem's own flags (the Makefile's, less -Werror and -march): C99, no errno or trap semantics
LIBDEM_CFLAGS = ["-std=c99", "-O3", "-fno-math-errno", "-fno-trapping-math", "-fopenmp", "-fvisibility=hidden"]


def make_builder(archive: Path | None = None) -> cffi.FFI:
    """The extension over build/libdem.a (archive given) or over libdem's sources (None; paths
    relative to the project root, as setuptools wants them)."""
    ffi = cffi.FFI()
    ffi.cdef(cdef_source())
    libs = pkg_config("--libs")
    cflags = pkg_config("--cflags")
    if archive is None:
        sources = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "libdem").glob("*.c"))
        headers = sorted(str(p.relative_to(ROOT)) for p in [*(ROOT / "libdem").glob("*.h"), *INCLUDE.glob("*.h")])
        extra = {"sources": sources, "depends": headers,  # a changed header recompiles (setuptools checks these)
                 "include_dirs": ["include", "libdem"], "extra_compile_args": LIBDEM_CFLAGS + cflags}
    else:
        extra = {"extra_objects": [str(archive)], "include_dirs": [str(ROOT / "include")],
                 "extra_compile_args": ["-O2"] + cflags}
    ffi.set_source(
        "pydem._libdem",
        '#include "dem/dem.h"',
        library_dirs=[a[2:] for a in libs if a.startswith("-L")],
        libraries=[a[2:] for a in libs if a.startswith("-l")] + ["m"],
        extra_link_args=["-fopenmp"],
        **extra,
    )
    return ffi


def build() -> Path:
    archive = ROOT / "build" / "libdem.a"
    if not archive.exists():
        sys.exit(f"pydem: {archive} is missing; run `make lib` first")
    ffi = make_builder(archive)
    tmp = ROOT / "build" / "pydem"
    built = Path(ffi.compile(tmpdir=str(tmp), verbose=False))
    target = ROOT / "pydem" / built.name
    # copy, then rename over the old module: processes that have it loaded (a running campaign)
    # keep their mapping; writing into the loaded file in place would crash them
    staging = target.with_name(f".{target.name}.new")
    shutil.copyfile(built, staging)
    os.replace(staging, target)
    return target


if __name__ == "__main__":
    print(f"pydem: built {build().relative_to(ROOT)}")
else:  # imported by setuptools (cffi_modules)
    ffibuilder = make_builder()
