"""Writes the STL fuzz corpus kept in tests/data/stl_corpus: two valid seeds (ASCII and
binary cube) and deterministic mutations of them (bit flips, truncations, wrong triangle
counts, NaN/inf, junk tokens). tests/c/test_stl.c loads every file and requires a clean
status, never a crash; it also mutates the seeds further in memory.

    python3 scripts/make_stl_corpus.py      # rewrites the corpus (seeded, reproducible)
"""
import math
import random
import struct
from pathlib import Path

from make_geometry import ascii_stl

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "stl_corpus"

CUBE = [  # 12 triangles of the unit cube
    ((0, 0, 0), (1, 1, 0), (1, 0, 0)), ((0, 0, 0), (0, 1, 0), (1, 1, 0)),
    ((0, 0, 1), (1, 0, 1), (1, 1, 1)), ((0, 0, 1), (1, 1, 1), (0, 1, 1)),
    ((0, 0, 0), (1, 0, 0), (1, 0, 1)), ((0, 0, 0), (1, 0, 1), (0, 0, 1)),
    ((0, 1, 0), (1, 1, 1), (1, 1, 0)), ((0, 1, 0), (0, 1, 1), (1, 1, 1)),
    ((0, 0, 0), (0, 0, 1), (0, 1, 1)), ((0, 0, 0), (0, 1, 1), (0, 1, 0)),
    ((1, 0, 0), (1, 1, 0), (1, 1, 1)), ((1, 0, 0), (1, 1, 1), (1, 0, 1)),
]


def binary_stl(tris, header=b"binary cube"):
    out = header.ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
    return out


def mutations(seed: bytes, rng: random.Random, n: int):
    for _ in range(n):
        b = bytearray(seed)
        kind = rng.randrange(5)
        if kind == 0:  # bit flips
            for _ in range(rng.randint(1, 8)):
                i = rng.randrange(len(b))
                b[i] ^= 1 << rng.randrange(8)
        elif kind == 1:  # truncation
            b = b[: rng.randrange(len(b))]
        elif kind == 2:  # random bytes overwritten
            i = rng.randrange(len(b))
            b[i:i + 4] = bytes(rng.randrange(256) for _ in range(4))
        elif kind == 3:  # duplicated chunk
            i = rng.randrange(len(b))
            b = b[:i] + b[i:i + rng.randint(1, 60)] + b[i:]
        else:  # deletion
            i = rng.randrange(len(b))
            del b[i:i + rng.randint(1, 30)]
        yield bytes(b)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    for f in OUT.glob("*.stl"):
        f.unlink()
    rng = random.Random(20261121)
    a, b = ascii_stl("cube", CUBE).encode(), binary_stl(CUBE)
    files = {
        "seed_ascii_cube.stl": a,
        "seed_binary_cube.stl": b,
        "binary_header_says_solid.stl": binary_stl(CUBE, b"solid but binary"),
        "empty.stl": b"",
        "truncated_binary.stl": b[:-17],
        "count_too_large.stl": b[:80] + struct.pack("<I", 13) + b[84:],
        "count_huge.stl": b[:80] + struct.pack("<I", 0xFFFFFFFF) + b[84:],
        "nan_ascii.stl": a.replace(b"vertex 1 1 0", b"vertex nan 1 0", 1),
        "inf_ascii.stl": a.replace(b"vertex 1 1 0", b"vertex 1 inf 0", 1),
        "nan_binary.stl": binary_stl([((0, 0, 0), (math.nan, 1, 0), (1, 0, 0))] + CUBE[1:]),
        "missing_endsolid.stl": a.replace(b"endsolid cube\n", b""),
        "junk_token.stl": a.replace(b"outer loop", b"outer lop", 1),
        "short_header.stl": b"\0" * 50,
        "all_degenerate.stl": ascii_stl("degenerate", [((0, 0, 0), (1, 1, 1), (2, 2, 2)), ((0, 0, 0), (0, 0, 0), (1, 0, 0))]).encode(),
        "nul_in_ascii.stl": a[:100] + b"\0" + a[101:],
    }
    for k, m in enumerate(mutations(a, rng, 20)):
        files[f"mut_ascii_{k:02d}.stl"] = m
    for k, m in enumerate(mutations(b, rng, 20)):
        files[f"mut_binary_{k:02d}.stl"] = m
    for name, data in files.items():
        (OUT / name).write_bytes(data)
    print(f"{len(files)} files in {OUT}")


if __name__ == "__main__":
    main()
