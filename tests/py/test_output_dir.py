"""An output directory is written whole or not at all (pydem/output_dir.py): a failure while
writing — here a full disk, simulated — leaves an earlier output as it was and no partial
directory; a directory of the user's own files is never taken over."""
import errno
from pathlib import Path

import pytest

from pydem import cli, output_dir
from pydem.calibration import material_card

ROOT = Path(__file__).resolve().parents[2]
ROWS = ("material,test,quantity,value,uncertainty,unit,conditions,use,source\n"
        "m,aor,angle_of_repose,31,0.5,deg,,calibrate,s\nm,aor,bulk_density,1480,10,kg/m^3,,calibrate,s\n")


def run(meas: Path, out: Path) -> int:
    return cli.main(["diagnose", str(meas), "--material", "m", "--out", str(out),
                     "--stores", str(ROOT / "data/campaigns/diag_aor_tiny.h5")])


def test_full_disk_leaves_the_earlier_output(tmp_path, monkeypatch, capsys):
    meas = tmp_path / "m.csv"
    meas.write_text(ROWS)
    out = tmp_path / "out"
    assert run(meas, out) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "diagnosis.json" in before

    def full(*_a, **_k):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(material_card, "write", full)
    assert run(meas, out) == 1
    assert "No space left on device" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # the earlier output, byte for byte
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv", "out"]  # no partial directory left


def test_first_failure_leaves_nothing(tmp_path, monkeypatch):
    meas = tmp_path / "m.csv"
    meas.write_text(ROWS)
    monkeypatch.setattr(material_card, "write", lambda *a, **k: (_ for _ in ()).throw(OSError(errno.ENOSPC, "full")))
    assert run(meas, tmp_path / "out") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv"]


def test_a_users_directory_is_never_taken_over(tmp_path):
    (tmp_path / "thesis.tex").write_text("x")
    with pytest.raises(output_dir.OutputError, match="not an earlier pydem output"):
        output_dir.check(tmp_path)
    with pytest.raises(output_dir.OutputError, match="a file is in the way"):
        output_dir.check(tmp_path / "thesis.tex")
    output_dir.check(tmp_path / "new" / "deeper")  # parents are made, the output itself is not
    assert (tmp_path / "new").is_dir() and not (tmp_path / "new" / "deeper").exists()


def test_the_default_diagnosis_output_is_one_folder_per_material():
    """`pydem diagnose` without --out writes build/diagnosis/<material>: a second material never
    meets the first one's output (or the demo's); a name that is no plain file name is not a path."""
    import argparse
    from pydem.cli_inputs import output_of
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd")
    from pydem import cli_diagnose
    cli_diagnose.add_parser(sub)
    args = lambda *a: ap.parse_args(["diagnose", "m.csv", *a])  # noqa: E731
    assert output_of(args("--material", "iron_ore-2")) == "build/diagnosis/iron_ore-2"
    assert output_of(args("--material", "../../etc")) == "build/diagnosis/material"
    assert output_of(args("--material", "x", "--out", "mine")) == "mine"
