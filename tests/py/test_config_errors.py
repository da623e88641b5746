"""Rig configurations refuse what they would otherwise invent: a fractional count, a boolean as
a number, and a key that silently overwrites keys given before it (the hopper's `case`)."""
import pytest

from pydem.rigs import ConfigError, HopperConfig, AorConfig, load


def test_whole_numbers_and_booleans(tmp_path):
    with pytest.raises(ConfigError, match="particles: expected a whole number, got '100.5'"):
        load(HopperConfig, "tiny", None, ["particles=100.5"])
    assert load(HopperConfig, "tiny", None, ["particles=300.0"]).particles == 300
    toml = tmp_path / "c.toml"
    toml.write_text("friction = true\n")
    with pytest.raises(ConfigError, match="friction: expected a number, got True"):
        load(AorConfig, "tiny", toml)


def test_a_case_does_not_silently_override_earlier_keys():
    with pytest.raises(ConfigError, match=r"case=A-1 sets particles = 620, overriding particles given before it"):
        load(HopperConfig, "tiny", None, ["particles=300", "case=A-1"])
    cfg = load(HopperConfig, "tiny", None, ["case=A-1", "particles=300"])  # later keys win
    assert cfg.particles == 300 and cfg.case == "A-1"
