#!/usr/bin/env bash
# Set up (virtualenv + build) and run the demo: identify the demo plant, then diagnose the same plant with a
# hidden dashpot (the diagnosis names it, with its held-out gain); the report lands in ./demo_report.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_venv.sh" ""
# The report folder is the demo's own: a rerun replaces it whole (--overwrite), never mixes runs.
"$VENV/bin/bouc-wen-id" demo --out "${1:-demo_report}" --overwrite
