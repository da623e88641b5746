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
    for kind in "" _replicates; do
        name=diag_${rig}_${preset}${kind}
        echo "== $name"
        .venv/bin/pydem campaign run data/campaigns/$name.toml --store data/campaigns/$name.h5 --workers "$workers"
    done
done
if [ "$preset" = default ]; then  # the hopper's size-spread runs (the two-size runs above pooled into them)
    echo "== diag_hopper_default_spread"
    .venv/bin/pydem campaign run data/campaigns/diag_hopper_default_spread.toml \
        --store data/campaigns/diag_hopper_default_spread.h5 --workers "$workers"
fi
