"""Summarise bench/results/packed_bed.csv as a Markdown table (median, min-max over repeats).

    python3 bench/summarize.py [bench/results/packed_bed.csv]
"""
import csv
import statistics
import sys
from collections import defaultdict


def split(rs):
    """Median time split; contacts = the force sweep minus its estimated integration share."""
    nb = statistics.median(float(r["frac_neighbor"]) for r in rs)
    integ = statistics.median(float(r["frac_integration_est"]) for r in rs)
    return f"{100 * nb:.1f} / {100 * (1 - nb - integ):.1f} / {100 * integ:.1f} %"


def cycles(rs):
    """Median hardware cycles per particle-step and clock (1-thread runs where counted), else '–'."""
    got = [r for r in rs if r.get("cycles_per_particle_step")]
    if not got:
        return "–"
    cps = statistics.median(float(r["cycles_per_particle_step"]) for r in got)
    ghz = statistics.median(float(r["clock_ghz"]) for r in got)
    return f"{cps:.0f} @ {ghz:.2f}"


def main(path="bench/results/packed_bed.csv"):
    rows = defaultdict(list)
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            rows[(int(r["particles"]), float(r["mu_r"]), int(r["threads"]))].append(r)
    print("| particles | μ_r | threads | M particle-steps/s (median, min–max) | runs | contacts/particle "
          "| time: neighbour / contacts / integration | libdem B/particle | peak RSS MiB | cycles/particle-step @ GHz |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key in sorted(rows):
        rs = rows[key]
        rates = [float(r["mpart_steps_per_s"]) for r in rs]
        spread = f"{min(rates):.2f}–{max(rates):.2f}" if len(rates) > 1 else "single run"
        print(f"| {key[0]:,} | {key[1]:.1f} | {key[2]} | {statistics.median(rates):.2f} ({spread}) | {len(rs)} "
              f"| {float(rs[0]['contacts_per_particle']):.2f} "
              f"| {split(rs)} "
              f"| {int(float(rs[0]['libdem_bytes_per_particle']))} | {float(rs[0]['peak_rss_mib']):.1f} "
              f"| {cycles(rs)} |")


if __name__ == "__main__":
    main(*sys.argv[1:])
