#!/bin/sh
# After the bench rows (queue.sh): the sensor lag's power by simulation at its two "adequate" misses.
cd "$(dirname "$0")/../.." || exit 1
while ! grep -q "end viscous@x" studies/bench48/queue.log; do sleep 10; done
date -u +"%H:%M:%S start lag_power" >> studies/bench48/queue.log
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 PYTHONPATH=python nice -n 19 /work/main/.venv/bin/python \
  studies/bench48/lag_power.py 35014 35019 --draws 10 > studies/bench48/lag_power.log 2>&1
date -u +"%H:%M:%S end lag_power" >> studies/bench48/queue.log
