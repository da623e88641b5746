#!/bin/sh
# Runs (or resumes) the diagnosis campaigns in data/campaigns/ one after the other: each store is
# created on the first call and continued on every later one; finished runs are never redone.
#   sh scripts/diagnosis_campaigns.sh tiny            # the CI stores (~15 min on 2 cores)
#   sh scripts/diagnosis_campaigns.sh default [N]     # the shipped stores (hours; N workers, default 2)
# Each run starts a fresh worker that imports pydem from this checkout: do not edit the code while
# a campaign runs here (a broken edit fails the runs it meets). For long campaigns beside
# development, run this script from a worktree at a fixed commit (git worktree add ../camp HEAD,
# `make pydem` there) and pass the stores' absolute paths; the store records the commit of each session.
set -e
cd "$(dirname "$0")/.."
preset=${1:-tiny}
workers=${2:-2}
for rig in hopper aor ring_shear; do
    # every diagnosis store of the rig at this preset: the main one, its replicates, and any
    # companion (the default hopper's size-spread store, into which its two-size runs pool)
    for toml in data/campaigns/diag_${rig}_${preset}*.toml; do
        name=$(basename "$toml" .toml)
        echo "== $name"
        .venv/bin/pydem campaign run "$toml" --store data/campaigns/$name.h5 --workers "$workers"
    done
done
