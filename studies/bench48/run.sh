#!/bin/sh
# One bench row at a time, as the brief asks: nice 19, one thread, one worker, the bench's own filter and seeds.
# usage: sh studies/bench48/run.sh NAME [bench args...]   -> studies/bench48/NAME.json, NAME.log
cd "$(dirname "$0")/../.." || exit 1
name=$1; shift
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONPATH=python \
  nice -n 19 /work/main/.venv/bin/python benches/diagnosis.py --workers 1 --cache target/benchcache \
  --json "studies/bench48/$name.json" "$@" > "studies/bench48/$name.log" 2>&1
