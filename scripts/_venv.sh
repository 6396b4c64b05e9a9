# Shared set-up, sourced by scripts/demo.sh and scripts/test.sh: a project virtualenv with the package
# built from source by maturin (needs the Rust toolchain) and the requested extras.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${BOUC_WEN_ID_VENV:-$ROOT/.venv}"
PY="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
    echo "==> creating virtualenv $VENV"
    "$PY" -m venv "$VENV"
fi
VPY="$VENV/bin/python"
command -v cargo >/dev/null || { echo "error: cargo (the Rust toolchain) is required to build the core" >&2; exit 1; }
echo "==> installing bouc_wen_id${1:+[$1]} into $VENV (maturin release build of the Rust core)"
"$VPY" -m pip install --quiet --upgrade pip
"$VPY" -m pip install --quiet "$ROOT${1:+[$1]}"
