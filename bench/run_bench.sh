#!/bin/sh
# Runs the packed-bed benchmark (DESIGN section 10) and writes bench/results/packed_bed.csv
# plus bench/results/machine.txt. Takes about 20 minutes on 2 cores (the 99,200-sphere bed
# dominates; the 20k cases are timed 3 times, alternating 1 and 2 threads). Usage: sh bench/run_bench.sh [quick]   (quick: 20k only, 2,000 settle steps)
set -e
cd "$(dirname "$0")/.."
out=bench/results
mkdir -p "$out"
csv=$out/packed_bed.csv
: > "$csv" # packed_bed writes the header into the empty file
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
