#!/usr/bin/env bash
# In-process A/B of the exact pair operators: revision REV's headers against the working
# tree's (bench/op_ab/op_ab.cpp says what it measures). Needs g++ and git; pins to core
# OP_AB_CPU (default 1).
#   bash bench/op_ab/run.sh REV [ROUNDS]
set -euo pipefail
rev=${1:?usage: bash bench/op_ab/run.sh REV [ROUNDS]}
rounds=${2:-150}
root=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
git -C "$root" archive "$rev" cpp/include | tar -x -C "$tmp"
old="$tmp/cpp/include/revcol" ren="$tmp/oldren/revcol"
mkdir -p "$ren/collide"
# the old FixedPoint, double-double and pair operators under other names; everything else
# (common.hpp, pair.hpp, trig.hpp, ...) comes from the working tree
sed 's/FixedPoint/FixedPointOld/g' "$old/fixed_point.hpp" > "$ren/fixed_point_old.hpp"
sed 's/namespace revcol::dd/namespace revcol::ddold/' "$old/double_double.hpp" > "$ren/double_double_old.hpp"
for d in 2 3; do
  sed "s/FixedPoint/FixedPointOld/g; s/Pair${d}DExact/Pair${d}DExactOld/g;
       s|revcol/fixed_point.hpp|revcol/fixed_point_old.hpp|;
       s|revcol/double_double.hpp|revcol/double_double_old.hpp|; s/dd::/ddold::/g" \
    "$old/collide/pair${d}d_exact.hpp" > "$ren/collide/pair${d}d_exact_old.hpp"
done
g++ -O3 -DNDEBUG -std=c++20 -ffp-contract=off -fno-fast-math -I "$tmp/oldren" -I "$root/cpp/include" \
  "$root/bench/op_ab/op_ab.cpp" -o "$tmp/op_ab"
echo "op_ab: $rev against the working tree, $rounds rounds, $(date -u '+%F %T UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
taskset -c "${OP_AB_CPU:-1}" "$tmp/op_ab" "$rounds"
