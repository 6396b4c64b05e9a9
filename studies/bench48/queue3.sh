#!/bin/sh
# After the lag's power (queue2.sh): degradation 10x seed 38010 ("explained in part") read: other noise
# draws and its own noise on the plain plant (studies/bench47/noise_swap.py), then the case on c5385d2's
# package (bench47's code, before levels47/nu47; the same Rust) from the bench cache.
cd "$(dirname "$0")/../.." || exit 1
while ! grep -q "end lag_power" studies/bench48/queue.log; do sleep 10; done
date -u +"%H:%M:%S start 38010" >> studies/bench48/queue.log
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
PYTHONPATH=python nice -n 19 /work/main/.venv/bin/python studies/bench47/noise_swap.py library degradation "" 10 38010 4 \
  > studies/bench48/deg_38010.txt 2>&1
echo "--- the case on c5385d2's package:" >> studies/bench48/deg_38010.txt
PYTHONPATH=/tmp/bench48_old/python nice -n 19 /work/main/.venv/bin/python studies/bench47/replay47.py target/benchcache \
  library degradation "" 10 38010 >> studies/bench48/deg_38010.txt 2>&1
echo "--- the case on this code:" >> studies/bench48/deg_38010.txt
PYTHONPATH=python nice -n 19 /work/main/.venv/bin/python studies/bench47/replay47.py target/benchcache \
  library degradation "" 10 38010 >> studies/bench48/deg_38010.txt 2>&1
date -u +"%H:%M:%S end 38010" >> studies/bench48/queue.log
