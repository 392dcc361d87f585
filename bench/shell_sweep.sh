#!/usr/bin/env bash
# The neighbour-list shell against the packing fraction (docs/engine.md, Throughput: the
# shell): collisions per second forward and back, one core, periodic box, exact mode, for
# each shell in SHELLS (diameters; 0 is the automatic rule) and each case in CASES.
#   bash bench/shell_sweep.sh [BIN] > bench/results/engine_shell.csv
set -euo pipefail
BIN=${1:-build/revcol-bench}
SHELLS=${SHELLS:-"0 0.4 0.6 0.8 1.0 1.4 2.4 4 8"}
CASES=${CASES:-"1:1000:0.1 1:1000:0.3 1:1000:0.5 2:1000:0.05 2:1000:0.1 2:1000:0.3 2:10000:0.5 3:10000:0.05 3:10000:0.1 3:10000:0.3 3:10000:0.45"}
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
echo "d,n,phi,shell,forward_per_s,reverse_per_s,events_per_collision"
for c in $CASES; do
  IFS=: read -r d n phi <<< "$c"
  for s in $SHELLS; do
    REVCOL_ENGINE="d=$d,n=$n,phi=$phi,boundary=periodic,warm=5,shell=$s" \
      "$BIN" --bench engine/custom --collisions $((n * 20)) --repeats 1 --json "$tmp" > /dev/null
    python3 -c "
import json, sys
m = {r['metric']: r['median'] for r in json.load(open('$tmp'))['results']}
print('$d,$n,$phi,$s,%.4g,%.4g,%.3f' % (m['forward_per_s'], m['reverse_per_s'], m['events_per_collision']))"
  done
done
