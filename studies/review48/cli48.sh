#!/bin/sh
# Review 48: the command line on one case's files written by sim48 (CSV t,u,y, one per experiment, no
# amplitude or frequency given); the terminal output goes to cli48_CASE.txt here.
# From the repository root:  sh studies/review48/cli48.sh CASE_ID
set -e
CASE=$1
OUT="$(dirname "$0")/cli48_$CASE.txt"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
export PYTHONPATH=python OMP_NUM_THREADS=1
nice -n 15 "${PY:-/work/main/.venv/bin/python}" "$(dirname "$0")/drive48.py" --write "$CASE" "$WORK/data"
echo "\$ bouc-wen-id diagnose DATA/*.csv --no-figures --out OUT    # DATA: drive48.py --write $CASE" > "$OUT"
nice -n 15 timeout 300 "${BIN:-/work/main/.venv/bin/bouc-wen-id}" diagnose "$WORK"/data/*.csv --no-figures \
  --out "$WORK/out" 2>&1 | sed "s#$WORK#TMP#g" >> "$OUT" || echo "(exit $?)" >> "$OUT"
