#!/bin/sh
# The brief's rows in its order, one after the other: the 60 nulls, then each 20-case row.
# Each entry is EFFECT:SIZES:NAME; EFFECT may carry a place (viscous@x, the bench's --only filter).
cd "$(dirname "$0")/../.." || exit 1
date -u +"%H:%M:%S start null" >> studies/bench48/queue.log
sh studies/bench48/run.sh null --only null --cases 0 --null 60
date -u +"%H:%M:%S end null" >> studies/bench48/queue.log
for row in sensor_lag:10:sensor_lag series_dashpot:10:series_dashpot iwan:10:iwan pi_u:10:pi_u \
    degradation:10,30:degradation stiffness_degradation:10:stiffness_degradation viscous@x:10:viscous_x; do
  eff=${row%%:*}; rest=${row#*:}; sz=${rest%%:*}; out=${rest#*:}
  date -u +"%H:%M:%S start $eff $sz" >> studies/bench48/queue.log
  sh studies/bench48/run.sh "$out" --only "$eff" --sizes "$sz" --cases 20 --null 0
  date -u +"%H:%M:%S end $eff $sz" >> studies/bench48/queue.log
done
