#!/bin/sh
# The packed bed beside a busy process (issue: a 2-thread run on a shared 2-core machine fell
# 3-9x below the 1-thread speed). One `busy` loop takes a core for the whole benchmark; rounds
# alternate 1 thread, 2 threads with libgomp's default wait policy (spin, then sleep), 2 threads
# with OMP_WAIT_POLICY=passive (sleep at once) and 2 threads with GOMP_SPINCOUNT=10000.
#   sh bench/contended_bed.sh [rounds] [binary]     (a settled 12k bed is made once in /tmp)
#   BUSY=0 sh bench/contended_bed.sh ...            the same rounds on a quiet machine (what the
#                                                   passive policy costs when nothing competes)
set -e
rounds=${1:-5}
bin=${2:-build/bench/packed_bed}
bed=/tmp/packed_bed_14.raw
[ -f "$bed" ] || "$bin" --n-side 14 --settle 6000 --settle-threads 1 --steps 1 --threads 1 --save "$bed" > /dev/null
if [ "${BUSY:-1}" != 0 ]; then
    sh -c 'while :; do :; done' &
    busy=$!
    trap 'kill $busy 2>/dev/null' EXIT
fi
rate() { grep -o '[0-9.]* M particle-steps/s' | cut -d' ' -f1; }
run() { "$bin" --n-side 14 --load "$bed" --settle 200 --steps 1500 --threads "$1" | rate; }
for r in $(seq "$rounds"); do
    a=$(run 1)
    b=$(run 2)
    c=$(OMP_WAIT_POLICY=passive run 2)
    e=$(GOMP_SPINCOUNT=10000 run 2)
    echo "round $r: 1 thread $a | 2 threads: default $b, passive $c, spincount 1e4 $e  (M particle-steps/s)"
done
