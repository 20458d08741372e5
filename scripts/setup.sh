#!/usr/bin/env bash
# Set up cuneate on a fresh Debian/Ubuntu machine: system tools (Icarus Verilog, a C++ toolchain
# and perl for Verilator), a virtual environment, and the Python dependencies. Safe to re-run:
# whatever is already installed is reused.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${VENV:-.venv}"
EXTRAS="${CUNEATE_EXTRAS:-test,synth}"

need_apt=()
command -v iverilog >/dev/null 2>&1 || need_apt+=(iverilog)
command -v make >/dev/null 2>&1 || need_apt+=(make)
command -v g++ >/dev/null 2>&1 || need_apt+=(g++)
command -v perl >/dev/null 2>&1 || need_apt+=(perl)
command -v z3 >/dev/null 2>&1 || need_apt+=(z3)
command -v chromium >/dev/null 2>&1 || need_apt+=(chromium)
if [ ${#need_apt[@]} -gt 0 ]; then
    echo "setup: installing system packages: ${need_apt[*]}"
    if [ "$(id -u)" = 0 ]; then
        SUDO=""
    elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        SUDO="sudo"
    else
        echo "setup: missing ${need_apt[*]}; run as root: apt-get update && apt-get install -y ${need_apt[*]}" >&2
        exit 1
    fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

PYTHON="${PYTHON:-}"
if [ -z "$PYTHON" ]; then
    for cand in python3.13 python3.12 python3.11 python3; do
        if command -v "$cand" >/dev/null 2>&1 && "$cand" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
            PYTHON="$cand"; break
        fi
    done
fi
if [ -z "$PYTHON" ]; then
    echo "setup: Python >= 3.11 with venv is required (apt-get install -y python3 python3-venv)" >&2
    exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
    echo "setup: creating $VENV with $PYTHON"
    "$PYTHON" -m venv "$VENV" || { echo "setup: venv failed; apt-get install -y python3-venv" >&2; exit 1; }
fi
# pip install, minus the notes pip prints for configured package locations that do not exist
# on this machine (index or find-links entries of the machine's pip configuration)
pip_quiet() {
    "$VENV/bin/python" -m pip "$@" 2> >(grep -v "^WARNING: Location '.*' is ignored: it is neither a file nor a directory\.$" >&2)
}
pip_quiet install -q --upgrade "pip>=23" "setuptools>=69" wheel
# the build backend warns about editable installs of mapped package folders; not actionable
PYTHONWARNINGS=ignore pip_quiet install -q -e ".[${EXTRAS}]"
"$VENV/bin/cuneate" doctor
