#!/bin/sh
# Cost against bed size: the packed bed (DESIGN section 10, mu_r 0) from 5,022 to 194,432
# spheres, all with the same protocol as make bench (settle 20,000 steps on 2 threads), then
# 2,000 timed steps on 1 thread; one CSV row each in bench/results/packed_bed_scaling.csv
# (the columns of packed_bed.csv). Instructions per particle-step are the work (flat = cost
# linear in N); cycles per particle-step add what the caches do (the touched state leaves the
# L3 cache between ~20k and ~100k spheres). Takes about 17 minutes on 2 cores.
# Usage: sh bench/scaling.sh
set -e
cd "$(dirname "$0")/.."
out=bench/results
mkdir -p "$out"
csv=$out/packed_bed_scaling.csv
: > "$csv" # packed_bed writes the header into the empty file
for n in 9 13 18 26 40 56; do
    build/bench/packed_bed --n-side "$n" --mu-r 0 --settle 20000 --steps 2000 --threads 1 --settle-threads 2 --csv "$csv"
done
echo "results: $csv"
