#!/bin/sh
# The rows of the brief, in its order, one after the other (after the 60 nulls).
cd "$(dirname "$0")/../.." || exit 1
while [ ! -s studies/bench47/null.json ]; do sleep 10; done
for row in series_dashpot:10 iwan:10 pi_u:10 sensor_lag:10 stiffness_degradation:10,30 pinching:10,30; do
  eff=${row%%:*}; sz=${row#*:}
  date -u +"%H:%M:%S start $eff $sz" >> studies/bench47/queue.log
  sh studies/bench47/run.sh "$eff" --only "$eff" --sizes "$sz" --cases 20 --null 0
  date -u +"%H:%M:%S end $eff" >> studies/bench47/queue.log
done
