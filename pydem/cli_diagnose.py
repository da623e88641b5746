"""`pydem diagnose`: where the base model fails against a measurement file, which candidate
effect is missing, and the error before and after adding it (docs/diagnosis.md).

    pydem diagnose data/measurements/synthetic_cohesive.csv --material synthetic_cohesive   # report in build/diagnosis/synthetic_cohesive
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from . import output_dir
from .cli_inputs import add_common, load_inputs, output_checked, output_of


def add_parser(sub):
    p = sub.add_parser("diagnose", help="calibrate, show where the model fails, name the missing effect, add it")
    add_common(p, "build/diagnosis/{material}")
    p.add_argument("--refine", type=int, default=0, metavar="N",
                   help="after the first pass, up to N DEM runs of the file's rigs where the surrogates' error decides "
                        "the answer, the surrogates corrected by them, and the diagnosis again (runs kept, resumable, in "
                        "<out>.refine; docs/diagnosis.md §8)")
    p.add_argument("--workers", type=int, default=None, help="worker processes of the refinement runs (default: the cores)")
    p.add_argument("--dask", metavar="ADDRESS", help="run the refinement runs on a Dask cluster, e.g. tcp://host:8786")
    p.add_argument("--refine-design", choices=("greedy", "fixed"), default="greedy",
                   help="where the refinement runs go: greedy (the net error the verdict's predictions lose, the "
                        "default) or fixed (a Sobol design over the posterior's box, the simple alternative)")
    p.set_defaults(func=main)


MAX_REFINE = 4096


def main(args) -> int:
    from .calibration import report
    from .calibration.diagnose import diagnose
    t0 = time.perf_counter()
    say = lambda msg: print(msg, flush=True)  # noqa: E731
    args.out = output_of(args)
    if not output_checked(args.out, "diagnose"):
        return 2
    refine_dir = Path(str(args.out).rstrip("/") + ".refine")
    if args.refine and (not 0 < args.refine <= MAX_REFINE or (refine_dir.exists() and not refine_dir.is_dir())
                        or (args.workers is not None and args.workers < 1)):
        print(f"pydem diagnose: --refine takes 1..{MAX_REFINE} runs, --workers at least 1, and {refine_dir} must be a "
              f"directory or absent (got --refine {args.refine}, --workers {args.workers})", file=sys.stderr)
        return 2
    loaded = load_inputs(args, "diagnose", say)
    if loaded is None:
        return 2
    setup, obs, skipped, scaling = loaded
    runs = None
    if args.refine:
        from .calibration import refine
        try:
            runs = refine.saved_plan(refine_dir, obs, args.refine, setup.stores, args.refine_design)
        except (ValueError, OSError) as exc:
            print(f"pydem diagnose: {exc}", file=sys.stderr)
            return 2
    say(f"diagnosing {args.material}: {len(obs)} measurements, candidates "
        f"{', '.join(c.name for c in setup.candidates)} (stores: libdem {setup.physics})")
    try:
        d = diagnose(args.material, obs, setup.nets, setup.ranges, setup.candidates, say)
    except ValueError as exc:
        print(f"pydem diagnose: {exc}", file=sys.stderr)
        return 2
    refinement = None
    if args.refine:
        if runs is None:
            runs = (refine.plan(d, obs, setup.nets, setup.candidates, setup.ranges, args.refine)
                    if args.refine_design == "greedy" else
                    refine.plan_fixed(d, obs, setup.candidates, setup.ranges, args.refine))
            refine.save_plan(refine_dir, runs, obs, args.refine, setup.stores, args.refine_design)
        import os
        from .campaign.workers import WorkerStartError
        try:
            entries = refine.run_plan(runs, setup.stores, refine_dir, args.workers or os.cpu_count() or 1, say, args.dask)
        except (WorkerStartError, OSError, TimeoutError) as exc:
            print(f"pydem diagnose: the refinement runs cannot start ({exc}); runs done so far are kept in {refine_dir}",
                  file=sys.stderr)
            return 2
        nets = refine.corrected_nets(setup.nets, entries)
        say(f"second pass, on the surrogates corrected by {sum('metrics' in e for e in entries)} runs:")
        first, d = d, diagnose(args.material, obs, nets, setup.ranges, setup.candidates, say)
        refinement = refine.summary(first, d, entries, nets, obs) | {"folder": str(refine_dir)}
    d.notes += [f"left out: {line}" for line in skipped] + [f"material: {line}" for line in scaling.notes(setup.ranges)]
    from .calibration.reach import name_campaigns
    for line in name_campaigns(d.reach, setup.stores, {o.quantity.rig for o in obs}):
        say(f"  at an edge: {line}")
    from .provenance import provenance
    context = {"provenance": provenance(), "measurements": str(args.measurements),
               "stores": setup.store_provenance(), "libdem_of_stores": setup.physics, "material": scaling.as_dict(),
               "refinement": refinement}
    if args.confirm:
        from .calibration.confirm import confirm
        from .progress import RunProgress
        fit = d.after if d.after is not None else d.base
        context["confirm"] = confirm(setup, fit, obs, args.threads, say, RunProgress())
    from .calibration import material_card  # the final model: with the effect when one was added
    try:
        with output_dir.staged(args.out) as tmp:
            report.write(d, tmp, context)
            material_card.write(material_card.card(args.material, setup, d.after if d.after is not None else d.base,
                                                   setup.candidates, d.verdict, report.verdict_line(d), scaling), tmp)
    except OSError as exc:
        print(f"pydem diagnose: cannot write the output ({exc}); an earlier output in {args.out} is left as it was",
              file=sys.stderr)
        return 1
    say(f"verdict: {d.verdict}" + (f" ({' + '.join(d.effects)})" if d.effect else "") + f" — {report.verdict_line(d)}")
    for r in [c for c in d.candidates if c.effect == d.effect] + d.added if d.effect else []:
        say(f"  {r.effect}: {r.estimate:.4g} {r.unit} (95 % {r.estimate_lo:.4g}-{r.estimate_hi:.4g}), the final model's")
    say(f"report: {Path(args.out) / 'report.html'} ({time.perf_counter() - t0:.0f} s)")
    return 0
