#!/usr/bin/env bash
# Set up (virtualenv + build) and run every check: Rust format/lint/tests, Python lint and format, types
# (the package, its tests and examples), stub check, pytest.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_venv.sh" "test"
cd "$ROOT"
echo "==> cargo fmt --check";      cargo fmt --check
echo "==> cargo clippy";           cargo clippy --all-targets --features python -- -D warnings
echo "==> cargo test";             cargo test
echo "==> ruff";                   "$VENV/bin/ruff" check python tests benches examples studies
echo "==> ruff format --check";    "$VENV/bin/ruff" format --check python tests benches examples studies
echo "==> mypy (strict)";          "$VENV/bin/mypy" python/bouc_wen_id
echo "==> mypy (strict): tests, examples"; "$VENV/bin/mypy" --strict tests examples
echo "==> stubtest _core.pyi";     (cd /tmp && "$VENV/bin/python" -m mypy.stubtest bouc_wen_id._core)
if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then
    # tests/test_browser.py opens the diagnosis report in headless Chromium, from the distribution's packages.
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        echo "==> apt-get install chromium chromium-driver (the report's browser test)"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null
    else
        echo "warning: chromium/chromedriver missing and apt-get needs root: tests/test_browser.py will skip" >&2
    fi
fi
echo "==> pytest"
# Run against the installed wheel, not the source tree, so that a packaging slip shows up here.
"$VENV/bin/python" -m pytest -p no:cacheprovider --rootdir "$ROOT" --import-mode=importlib "$ROOT/tests" "$@"
