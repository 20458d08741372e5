#!/usr/bin/env bash
# The independent NIR consumer's own environment (snnTorch on a CPU build of PyTorch), kept
# apart from cuneate's: build/crosscheck-venv (or $CROSSCHECK_VENV). Safe to re-run: an
# environment that already imports snntorch and nir is reused. Prints the python to use.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${CROSSCHECK_VENV:-build/crosscheck-venv}"
PYTHON="${PYTHON:-python3}"
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import snntorch, nirtorch, nir, torch" 2>/dev/null; then
    echo "$VENV/bin/python"
    exit 0
fi
mkdir -p "$(dirname "$VENV")"
[ -x "$VENV/bin/python" ] || "$PYTHON" -m venv "$VENV" >&2
pip_quiet() {
    "$VENV/bin/python" -m pip "$@" 2> >(grep -v "^WARNING: Location '.*' is ignored" >&2) >&2
}
pip_quiet install -q --upgrade pip
# torch first, pinned to the CPU build (a bare "torch" would pull a multi-GB CUDA build)
pip_quiet install -q "torch==2.13.0"
pip_quiet install -q "snntorch==1.0.0" "nirtorch==2.6" "nir>=1.0.8,<2" "torch==2.13.0"
"$VENV/bin/python" -c "import snntorch, nirtorch, nir, torch" >&2
echo "$VENV/bin/python"
