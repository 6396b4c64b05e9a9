#!/bin/sh
# The rest of the brief's rows after sensor lag, pinching split by size so that 10x lands before the deadline.
cd "$(dirname "$0")/../.." || exit 1
while [ ! -s studies/bench47/sensor_lag.json ]; do sleep 10; done
for row in stiffness_degradation:10,30:stiffness_degradation pinching:10:pinching10 pinching:30:pinching30; do
  eff=${row%%:*}; rest=${row#*:}; sz=${rest%%:*}; out=${rest#*:}
  date -u +"%H:%M:%S start $eff $sz" >> studies/bench47/queue.log
  sh studies/bench47/run.sh "$out" --only "$eff" --sizes "$sz" --cases 20 --null 0
  date -u +"%H:%M:%S end $eff $sz" >> studies/bench47/queue.log
done
