#!/bin/sh
# A/B of two packed_bed builds, run side by side (one core each) on the same settled 20k bed,
# so both see the same machine at the same moment: this VM's speed drifts by up to 2x over
# minutes, which swamps 10-20 % effects in back-to-back runs, but not in a paired ratio.
#   sh bench/ab_packed_bed.sh OLD_BINARY NEW_BINARY [rounds]
# OLD/NEW: packed_bed binaries, e.g. one built at the previous commit (git worktree + make
# build/bench/packed_bed). Prints one line per round and mu_r, and the geometric-mean ratio.
set -e
old=$1 new=$2 rounds=${3:-3}
bed=${BED:-/tmp/packed_bed_20k.raw}
[ -f "$bed" ] || "$new" --n-side 18 --settle 20000 --settle-threads 2 --steps 1 --threads 1 --save "$bed" > /dev/null
tmp=$(mktemp -d)
for r in $(seq "$rounds"); do
    for mu in 0.0 0.1; do
        "$old" --load "$bed" --mu-r "$mu" --settle 200 --steps 2000 --threads 1 > "$tmp/old" &
        "$new" --load "$bed" --mu-r "$mu" --settle 200 --steps 2000 --threads 1 > "$tmp/new"
        wait
        a=$(grep -o '[0-9.]* M particle-steps/s' "$tmp/old" | cut -d' ' -f1)
        b=$(grep -o '[0-9.]* M particle-steps/s' "$tmp/new" | cut -d' ' -f1)
        echo "round $r mu_r $mu: old $a new $b M particle-steps/s, ratio $(echo "$b $a" | awk '{printf "%.3f", $1 / $2}')"
    done
done | tee "$tmp/log"
for mu in 0.0 0.1; do
    grep "mu_r $mu:" "$tmp/log" | awk -v mu="$mu" '{s += log($NF); n++} END {printf "mu_r %s: geometric-mean ratio new/old %.3f over %d rounds\n", mu, exp(s / n), n}'
done
rm -rf "$tmp"
