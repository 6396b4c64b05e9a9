#!/bin/sh
# Session 47 (nu47): main (PYTHONPATH=/work/main/python, c5385d2) and this branch on the same cases, one
# process at a time: review 44's simulator (measure45.py) and tests/degradation_sim.py's RK4 (rk4_46.py).
#     sh studies/nu47/paired47.sh > studies/nu47/paired47.txt
export OMP_NUM_THREADS=1
PY=/work/main/.venv/bin/python
for code in /work/main/python python; do
  echo "## $code"
  for a in "nu 30 A rev 1 4" "nu 30 E rev 1 3" "nu 30 B rev 1 2" "nu 10 A rev 1 3"; do
    PYTHONPATH=$code nice -n 10 $PY studies/eta45/measure45.py $a
  done
  PYTHONPATH=$code nice -n 10 $PY studies/nu46/rk4_46.py 0.005 1,2,3,4,5,6
done
