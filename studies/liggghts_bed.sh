#!/bin/sh
# libdem against LIGGGHTS on the same packed bed (DESIGN section 10: 20,088 spheres, Hertz with
# tangential history, EPSD2 rolling at mu_r 0.1 and without rolling friction, dt 1e-5 s, skin
# 0.2 mm), one core each, alternating: settle 20,000 steps from the lattice, then time 5,000.
#   [NSIDE=40] [MU_R='0.1 0.0'] sh studies/liggghts_bed.sh LMP_SERIAL [rounds]   (NSIDE 40: the 99,200-sphere bed)
# LMP_SERIAL: a LIGGGHTS-PUBLIC serial build (fetch github:CFDEMproject/LIGGGHTS-PUBLIC, then in
# src/: make stubs; make serial CCFLAGS="-O3 -march=native -fPIC -std=c++11 -w"). Prints one line
# per run (M particle-steps/s and contacts per particle of the timed part) and the median ratio.
set -e
lmp=$1 rounds=${2:-2} nside=${NSIDE:-18} mus=${MU_R:-0.1 0.0}
n=$((nside * nside * 62))
here=$(cd "$(dirname "$0")" && pwd)
dem=${PACKED_BED:-$here/../build/bench/packed_bed}
tmp=$(mktemp -d)
for r in $(seq "$rounds"); do
    for mu in $mus; do
        (cd "$tmp" && "$lmp" -var nside "$nside" -var mur "$mu" -in "$here/liggghts/in.packed_bed" > lig.log)
        loop=$(grep -o 'Loop time of [0-9.e+-]* on 1 procs for 5000 steps' "$tmp/lig.log" | awk '{print $4}')
        contacts=$(awk '/Step +Atoms +cnsum/ {f = 1; next} f && $1 == 25000 {print $3 / $2}' "$tmp/lig.log")
        lig=$(echo "$loop" | awk -v n="$n" '{printf "%.3f", n * 5000 / $1 / 1e6}')
        "$dem" --n-side "$nside" --mu-r "$mu" --settle 20000 --settle-threads 1 --steps 5000 --threads 1 > "$tmp/dem.log"
        libdem=$(grep -o '[0-9.]* M particle-steps/s' "$tmp/dem.log" | cut -d' ' -f1)
        dc=$(grep -o 'contacts/particle [0-9.]*' "$tmp/dem.log" | cut -d' ' -f2)
        echo "round $r mu_r $mu: LIGGGHTS $lig M particle-steps/s (contacts/particle $contacts), libdem $libdem ($dc), ratio $(echo "$libdem $lig" | awk '{printf "%.2f", $1 / $2}')"
    done
done | tee "$tmp/log"
for mu in $mus; do
    grep "mu_r $mu:" "$tmp/log" | awk -v mu="$mu" '{print $NF}' | sort -n | awk -v mu="$mu" '{v[NR] = $1} END {printf "mu_r %s: libdem / LIGGGHTS median %.2f over %d rounds\n", mu, (NR % 2) ? v[(NR + 1) / 2] : 0.5 * (v[NR / 2] + v[NR / 2 + 1]), NR}'
done
rm -rf "$tmp"
