"""The bad-input corpus of the command line: every probe must end with a one-line message that
names the problem and a non-zero exit code — never a traceback, never exit 0 with an invented
result. Run alone (`pytest tests/py/test_bad_inputs.py -v`) it is the probe count of the
robustness issue."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEADER = "material,test,quantity,value,uncertainty,unit,conditions,use,source\n"


def files(tmp: Path) -> dict:
    made = {
        "g_cm3.csv": HEADER + "x,poured,bulk_density,1.55,0.05,g/cm^3,,calibrate,s\nx,poured,bulk_density,1.55,0.05,kg/m^3,,compare,s\n",
        "unknown_test.csv": HEADER + "x,silo,flow,1,0.1,,,calibrate,s\n",
        "dup.csv": HEADER + "x,aor,angle_of_repose,30,0.5,deg,,calibrate,s\nx,aor,angle_of_repose,30,0.5,deg,,calibrate,s\n",
        "neg_u.csv": HEADER + "x,aor,angle_of_repose,30,-0.5,deg,,calibrate,s\n",
        "hopper_only.csv": HEADER + "x,hopper,mass_flow_rate,0.5,0.01,kg/s,slot_width=0.05,calibrate,s\n",
        "cond.csv": HEADER + "x,ring_shear,mu_ie_ps,0.5,0.01,,sigma=1,calibrate,s\n",
        "seed.toml": 'rig = "aor"\npreset = "tiny"\nseed = 1.5\n[ranges]\nfriction = [0.1, 0.5]\n',
        "bool.toml": "friction = true\n",
        "int_range.toml": 'rig = "aor"\npreset = "tiny"\n[ranges]\nfriction = [0.1, 0.5]\nparticles = [100, 600]\n',
        "long_field.csv": HEADER + "x,aor,angle_of_repose,30,0.5,deg,,calibrate," + "s" * 200000 + "\n",
        "many_rows.csv": HEADER + "".join(f"x,hopper,mass_flow_rate,0.5,0.01,kg/s,slot_width={0.03 + i * 1e-6:.6f},"
                                          f"calibrate,s\n" for i in range(2001)),
        "stl_bad.stl": "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n",
    }
    for name, text in made.items():
        (tmp / name).write_text(text)
    return {k: str(tmp / k) for k in made}


PROBES = [  # (argv with {file} placeholders, words the message must contain)
    (["rig", "hopper", "--preset", "tiny", "--set", "particles=100.5"], "expected a whole number"),
    (["rig", "hopper", "--preset", "tiny", "--set", "particles=300", "--set", "case=A-1"], "overriding particles"),
    (["rig", "aor", "--preset", "tiny", "--config", "{bool.toml}"], "friction: expected a number, got True"),
    (["rig", "aor", "--preset", "tiny", "--set", "friction=nan"], "friction is NaN"),
    (["rig", "aor", "--preset", "tiny", "--set", "friction=-1"], "out of range"),
    (["rig", "aor", "--preset", "huge"], "unknown preset"),
    (["rig", "aor", "--preset", "tiny", "--set", "effects.cohesion_sjkr.energy_density=1"], "has parameters"),
    (["rig", "hopper", "--preset", "tiny", "--out", "/nonexistent/dir/r.json"], "cannot write the output"),
    (["campaign", "run", "{seed.toml}", "--store", "{tmp}/s.h5"], "seed: expected an integer in 0..9223372036854775807"),
    (["campaign", "status", "{tmp}/none.h5"], "no such campaign store"),
    (["campaign", "run", "{int_range.toml}", "--store", "{tmp}/s.h5"], "ranges.particles: a design samples values "
                                                                       "between the ends, and particles: expected a whole number"),
    (["campaign", "export", str(ROOT / "data/campaigns/aor_tiny.h5"), "--csv", "/nonexistent/x.csv"], "No such file or directory"),
    (["compare", "{g_cm3.csv}", "--material", "x", "--dem", "r.json"], "is outside the physically possible range"),
    (["compare", "{unknown_test.csv}", "--material", "x", "--dem", "r.json"], "unknown test 'silo'"),
    (["compare", "{dup.csv}", "--material", "x", "--dem", "r.json"], "duplicate of line 2"),
    (["compare", "{neg_u.csv}", "--material", "x", "--dem", "r.json"], "must be positive"),
    (["compare", "{cond.csv}", "--material", "x", "--dem", "r.json"], "unknown condition 'sigma'"),
    (["calibrate", "{hopper_only.csv}", "--material", "x", "--stores", str(ROOT / "data/campaigns/diag_aor_tiny.h5"),
      "--out", "{tmp}/cal"], "can be compared with the campaigns"),
    (["calibrate", "{hopper_only.csv}", "--material", "x", "--samples", "0", "--out", "{tmp}/cal"],
     "--samples must lie in 1..4194304"),
    (["calibrate", "{hopper_only.csv}", "--material", "x", "--samples", "1000000000", "--out", "{tmp}/cal"],
     "--samples must lie in 1..4194304"),
    # limits, checked before any work
    (["rig", "aor", "--preset", "tiny", "--seed", "99999999999999999999"], "outside 0..9223372036854775807"),
    (["diagnose", "{long_field.csv}", "--material", "x"], "a line of 200044 characters; at most 4000"),
    (["diagnose", "{many_rows.csv}", "--material", "x"], "2001 rows; at most 2000 are read"),
    (["diagnose", "{hopper_only.csv}", "--material", "x", "--out", "{hopper_only.csv}"], "a file is in the way"),
    (["calibrate", "{hopper_only.csv}", "--material", "x", "--out", "{tmp}"], "not an earlier pydem output"),
    (["diagnose", "{hopper_only.csv}", "--material", "x", "--out", "/proc/pydem/out"], "cannot create its parent"),
    (["compare", "{hopper_only.csv}", "--material", "x"], "give --params"),
    (["diagnose", "{unknown_test.csv}", "--material", "x"], "unknown test 'silo'"),
    (["diagnose", "{hopper_only.csv}", "--material", "y"], "no rows for material 'y'"),
]


@pytest.mark.parametrize("argv,words", PROBES, ids=[" ".join(p[0][:3]) + f" #{i}" for i, p in enumerate(PROBES)])
def test_probe_gives_a_clean_error(tmp_path, argv, words):
    f = files(tmp_path)
    args = []
    for a in argv:
        for k, v in f.items():
            a = a.replace("{" + k + "}", v)
        args.append(a.replace("{tmp}", str(tmp_path)))
    # run in the test's own folder: a default --out (build/...) lands there, whatever the checkout holds
    r = subprocess.run([sys.executable, "-m", "pydem", *args], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode != 0, f"exit 0 for {args}: {r.stdout[-500:]}"
    assert "Traceback" not in r.stderr, r.stderr[-2000:]
    assert words in r.stderr, r.stderr[-1000:]
