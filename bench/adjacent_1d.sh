#!/usr/bin/env bash
# 1D: the rods-beside lists against another build's engine, side by side, alternated
# (docs/engine.md, "1D: the rods beside"). Prints CSV.
#   bash bench/adjacent_1d.sh NEW_BIN OLD_BIN
set -euo pipefail
NEW=$1
OLD=$2
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
echo "build,boundary,n,phi,forward_per_s,reverse_per_s,events_per_collision,engine_bytes"
for b in wall periodic; do
  for n in 1000 100000; do
    for phi in 0.1 0.3 0.5; do
      for which in new old new old; do
        bin=$NEW; [ "$which" = old ] && bin=$OLD
        REVCOL_ENGINE="d=1,n=$n,phi=$phi,boundary=$b,warm=5" \
          "$bin" --bench engine/custom --collisions $((n * 20)) --repeats 1 --json "$tmp" > /dev/null
        python3 -c "
import json
m = {r['metric']: r['median'] for r in json.load(open('$tmp'))['results']}
print('$which,$b,$n,$phi,%.4g,%.4g,%.3f,%d' % (m['forward_per_s'], m['reverse_per_s'], m['events_per_collision'], m['engine_bytes']))"
      done
    done
  done
done
