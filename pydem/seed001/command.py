"""`pydem images`: seed 001's image half on a hopper frame store — the Table 1 frame set, grey
relational analysis, the four CNNs compared, AlexNet-FC, the CNN-LSTM and the report
(pydem/seed001/cli.py; the networks need torch, the `[nn]` extra).

    pydem images gra --store data/seed001/frames_subset.h5
    pydem images point-to-point --store data/seed001/frames_subset.h5 --out /tmp/p2p --epochs 2
"""
from __future__ import annotations

import argparse
import sys


def add_parser(sub):
    p = sub.add_parser("images", add_help=False,
                       help="seed 001's hopper images: frames, hoppers, gra, compare, point-to-point, process, report")
    p.add_argument("args", nargs=argparse.REMAINDER, help="a subcommand and its options (pydem images --help)")
    p.set_defaults(func=lambda args: forward(args.args))  # reached only when a caller parses argv itself


def forward(argv: list[str]) -> int:
    """Runs pydem.seed001's command line on argv (pydem's own parser would take `--help` and the like
    for itself, so pydem.cli hands `images ...` over before parsing)."""
    try:
        from .cli import main as seed001
    except ImportError as exc:
        print(f"pydem images: the image networks need torch (pip install 'pydem[nn]'): {exc}", file=sys.stderr)
        return 2
    return seed001(argv, prog="pydem images")
