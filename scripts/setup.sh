#!/bin/sh
# Project set-up, idempotent and quick when already done: the system libraries (installed with
# apt-get only where they are missing and this is Debian/Ubuntu; elsewhere it says what to
# install) and the Python environment in .venv, with pydem installed editable (pyproject.toml)
# and its extras. Called by `make test`, `make demo` and `make bench`.
set -e
cd "$(dirname "$0")/.."

# what the build and the tests need, checked by what they use rather than by package names
missing=""
pkg-config --version >/dev/null 2>&1 || missing="$missing pkg-config"
pkg-config --exists hdf5-serial 2>/dev/null || pkg-config --exists hdf5 2>/dev/null || missing="$missing libhdf5-dev"
pkg-config --exists libpng 2>/dev/null || missing="$missing libpng-dev"
[ -f /usr/include/cmocka.h ] || [ -f /usr/local/include/cmocka.h ] || missing="$missing libcmocka-dev"
command -v valgrind >/dev/null 2>&1 || missing="$missing valgrind"
command -v chromium >/dev/null 2>&1 || missing="$missing chromium"  # the reports' browser test
if [ -n "$missing" ]; then
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "setup: missing:$missing (Debian package names)." >&2
        echo "setup: install HDF5 and libpng with their headers and pkg-config files, cmocka, valgrind and" >&2
        echo "       chromium (the reports' browser test)" >&2
        echo "       with this system's package manager, then run make again." >&2
        exit 1
    fi
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null 2>&1 || { echo "setup: missing:$missing; run as root: apt-get install$missing" >&2; exit 1; }
        SUDO="sudo"
    fi
    echo "setup: installing system packages:$missing"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
    echo "setup: creating .venv"
    python3 -m venv .venv
fi
# pydem editable with every extra: the build tools first (no build isolation: nothing to download
# twice), then the package; redone when pyproject.toml or the build tools change
STAMP=.venv/.pydem-stamp
if [ ! -f "$STAMP" ] || ! cat scripts/requirements.txt pyproject.toml | cmp -s - "$STAMP"; then
    echo "setup: installing pydem (editable) and its dependencies into .venv"
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -r scripts/requirements.txt
    # an environment made by an older set-up: its path file and shell wrapper go
    SITE=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    rm -f "$SITE/pydem-repo.pth" .venv/bin/pydem
    .venv/bin/python -m pip install -q --no-build-isolation -e ".[nn,dask,test]"
    cat scripts/requirements.txt pyproject.toml > "$STAMP"
fi
