#!/usr/bin/env bash
# Set up (virtualenv + build) and run the demo identification; the report lands in ./demo_report.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_venv.sh" ""
# The report folder is the demo's own: a rerun replaces it whole (--overwrite), never mixes runs.
"$VENV/bin/bouc-wen-id" demo --out "${1:-demo_report}" --overwrite
