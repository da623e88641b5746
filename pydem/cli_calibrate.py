"""`pydem calibrate`: the base model's micro parameters from a measurement file over test
conditions — posterior with credible intervals and correlations, seed 000's ±5 % admissible set
screened natively over 2^20 combinations, the surrogates exported (libdem weights files and
standalone C), optional confirming DEM runs — and a report (docs/diagnosis.md §3).

    pydem calibrate data/measurements/glass_microbeads.csv --material glass_microbeads --out build/calibration
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from . import output_dir
from .cli_inputs import add_common, load_inputs, output_checked

# combinations screened at most: the screening holds a float64 per combination and row (2^22 x 30
# rows: 1 GiB), and seed 000 screened 10^6
MAX_SAMPLES = 2 ** 22


def add_parser(sub):
    p = sub.add_parser("calibrate", help="posterior of the micro parameters, seed 000's admissible set, exported nets")
    add_common(p, "build/calibration")
    p.add_argument("--window", type=float, default=0.05, help="seed 000's relative acceptance window (default 0.05)")
    p.add_argument("--samples", type=int, default=2 ** 20, help="combinations screened natively (default 2^20)")
    p.set_defaults(func=main)


def export_nets(nets: dict, directory: Path) -> list[Path]:
    """Every surrogate as a libdem weights file (<rig>__<quantity>.mlp) and a C99 pair (c/)."""
    from nn.export import write_c, write_weights
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for net in nets.values():
        a = net.mlp
        out.append(write_weights(a, directory / f"{net.name}.mlp"))
        write_c(a, directory / "c")
    return out


def main(args) -> int:
    from .calibration import report
    from .calibration.calibrate import calibrate
    t0 = time.perf_counter()
    say = lambda msg: print(msg, flush=True)  # noqa: E731
    if not 1 <= args.samples <= MAX_SAMPLES or not 0 < args.window < 1:
        print(f"pydem calibrate: --samples must lie in 1..{MAX_SAMPLES} (2^22) and --window in (0, 1) (got "
              f"{args.samples}, {args.window})", file=sys.stderr)
        return 2
    if not output_checked(args.out, "calibrate"):
        return 2
    loaded = load_inputs(args, "calibrate", say)
    if loaded is None:
        return 2
    setup, obs, skipped, scaling = loaded
    say(f"calibrating {args.material}: {len(obs)} measurements (stores: libdem {setup.physics})")
    c = calibrate(args.material, obs, setup.nets, setup.ranges, setup.candidates, args.window, args.samples,
                  args.threads, say)
    c.notes += [f"left out: {line}" for line in skipped] + [f"material: {line}" for line in scaling.notes(setup.ranges)]
    from .calibration.reach import name_campaigns
    for line in name_campaigns(c.reach, setup.stores, {o.quantity.rig for o in obs}):
        say(f"  at an edge: {line}")
    from .provenance import provenance
    context = {"provenance": provenance(), "measurements": str(args.measurements),
               "stores": setup.store_provenance(), "window": args.window, "samples": args.samples,
               "material": scaling.as_dict()}
    if args.confirm:
        from .calibration.confirm import confirm
        from .progress import RunProgress
        context["confirm"] = confirm(setup, c.fit, obs, args.threads, say, RunProgress())
    from .calibration import material_card
    out = Path(args.out)
    try:
        with output_dir.staged(out) as tmp:
            files = export_nets(setup.nets, tmp / "nets")
            report.write_calibration(c, tmp, context)
            material_card.write(material_card.card(args.material, setup, c.fit, setup.candidates, c.verdict,
                                                   report.calibration_line(c), scaling), tmp)
    except OSError as exc:
        print(f"pydem calibrate: cannot write the output ({exc}); an earlier output in {out} is left as it was",
              file=sys.stderr)
        return 1
    say(f"  {len(files)} surrogates exported to {out / 'nets'} (libdem weights files, C99 sources in nets/c)")
    say(f"verdict: {c.verdict} — {report.calibration_line(c)}")
    say(f"report: {out / 'report.html'} ({time.perf_counter() - t0:.0f} s)")
    return 0
