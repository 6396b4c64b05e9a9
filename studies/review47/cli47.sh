#!/bin/sh
# Review 47: the command line on files written by sim47 (CSV: t,u,y per experiment), terminal output kept.
#   sh studies/review47/cli47.sh CASE_ID [CASE_ID ...]  (from the repository root; writes cli47_CASE.txt here)
set -e
HERE=$(dirname "$0")
PY=${PY:-/work/main/.venv/bin/python}
BIN=${BIN:-/work/main/.venv/bin/bouc-wen-id}
for CASE in "$@"; do
  D=$(mktemp -d)
  PYTHONPATH=python OMP_NUM_THREADS=1 nice -n 15 "$PY" "$HERE/drive47.py" --write "$CASE" "$D/data"
  {
    echo "\$ bouc-wen-id diagnose DATA/*.csv --no-figures --out OUT    # DATA: drive47.py --write $CASE"
    PYTHONPATH=python OMP_NUM_THREADS=1 nice -n 15 timeout 300 "$BIN" diagnose "$D"/data/*.csv --no-figures --out "$D/out" 2>&1 || echo "(exit $?)"
  } | sed "s#$D#TMP#g" > "$HERE/cli47_$CASE.txt"
  rm -rf "$D"
done
