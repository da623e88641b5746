#!/bin/sh
# Runs the packed-bed benchmark (DESIGN section 10) and writes bench/results/packed_bed.csv
# plus bench/results/machine.txt. Takes about 20 minutes on 2 cores (the 99,200-sphere bed
# dominates; the 20k cases are timed 3 times, alternating 1 and 2 threads).
#   sh bench/run_bench.sh            the four cases of the issue
#   sh bench/run_bench.sh quick      20k only, 2,000 settle steps (a smoke run)
#   sh bench/run_bench.sh scaling    cost against bed size: 5,022 to 194,432 spheres, mu_r 0,
#       all with the same protocol (settle 20,000 steps on 2 threads, then 2,000 timed steps on
#       1 thread) -> bench/results/packed_bed_scaling.csv, ~14 minutes. Instructions per
#       particle-step are the work (flat = cost linear in N); cycles per particle-step add what
#       the caches do (the touched state leaves the L3 between ~20k and ~100k spheres).
set -e
cd "$(dirname "$0")/.."
out=bench/results
mkdir -p "$out"
csv=$out/packed_bed.csv
[ "$1" = scaling ] && csv=$out/packed_bed_scaling.csv
: > "$csv" # packed_bed writes the header into the empty file
if [ "$1" = scaling ]; then
    for n in 9 13 18 26 40 56; do
        build/bench/packed_bed --n-side "$n" --mu-r 0 --settle 20000 --steps 2000 --threads 1 --settle-threads 2 --csv "$csv"
    done
    echo "results: $csv"
    exit 0
fi
{
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
    echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
    echo "cores: $(nproc)"
    echo "compiler: $(${CC:-gcc} --version | head -1)"
    echo "libdem: $(sed -n 's/#define DEM_VERSION_STRING "\(.*\)"/\1/p' include/dem/base.h), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
} > "$out/machine.txt"
if [ "$1" = quick ]; then
    sizes="18"; settle=2000
else
    sizes="18 40"; settle=20000
fi
for n in $sizes; do
    repeat=1
    [ "$n" = 18 ] && repeat=3 # this VM's speed varies by +-15 % over minutes: repeat the cheap case
    for mu in 0 0.1; do
        build/bench/packed_bed --n-side "$n" --mu-r "$mu" --settle "$settle" --steps 5000 \
            --threads 1,2 --settle-threads 2 --repeat "$repeat" --csv "$csv"
    done
done
echo "results: $csv"
