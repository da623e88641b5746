#!/bin/sh
# Project set-up, idempotent and quick when already done: system packages (apt) and the
# Python environment in .venv. Called by `make test`, `make demo` and `make bench`.
set -e
cd "$(dirname "$0")/.."

SYS_PKGS="libhdf5-dev libpng-dev libcmocka-dev pkg-config valgrind"
missing=""
for p in $SYS_PKGS; do
    dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
if [ -n "$missing" ]; then
    echo "setup: installing system packages:$missing"
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing >/dev/null
fi

REQ=scripts/requirements.txt
STAMP=.venv/.requirements-stamp
if [ ! -x .venv/bin/python ]; then
    echo "setup: creating .venv"
    python3 -m venv .venv
fi
if [ ! -f "$STAMP" ] || ! cmp -s "$REQ" "$STAMP"; then
    echo "setup: installing Python packages from $REQ"
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -r "$REQ"
    cp "$REQ" "$STAMP"
fi
# `import pydem` from anywhere with .venv/bin/python, and a `pydem` command
SITE=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
[ -f "$SITE/pydem-repo.pth" ] || pwd > "$SITE/pydem-repo.pth"
if [ ! -x .venv/bin/pydem ]; then
    printf '#!/bin/sh\nexec "$(dirname "$0")/python" -m pydem "$@"\n' > .venv/bin/pydem
    chmod +x .venv/bin/pydem
fi
