#!/bin/sh
# One bench row at a time, as the brief asks: nice 19, one thread, one worker, the bench's own filter.
# usage: sh studies/bench47/run.sh NAME [bench args...]   -> studies/bench47/NAME.json, NAME.log
cd "$(dirname "$0")/../.." || exit 1
name=$1; shift
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONPATH=python \
  nice -n 19 /work/main/.venv/bin/python benches/diagnosis.py --workers 1 --cache target/benchcache \
  --json "studies/bench47/$name.json" "$@" > "studies/bench47/$name.log" 2>&1
