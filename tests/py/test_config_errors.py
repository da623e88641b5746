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


def test_an_effect_parameter_outside_libdems_range_is_refused_before_any_run():
    """libdem publishes each effect parameter's accepted range (dem_effect_param_range); a rig
    setting or a campaign range beyond it is refused when it is given, not run by run."""
    import pydem
    from pydem.campaign import CampaignSpec, SpecError
    cohesion = next(p for e in pydem.effects() if e["name"] == "cohesion_sjkr" for p in e["params"])
    assert (cohesion["min"], cohesion["max"]) == (0.0, 1e12)
    key = "effects.cohesion_sjkr.cohesion_energy_density"
    with pytest.raises(ConfigError, match=r"cohesion_energy_density = 1e\+13 J/m\^3 is outside libdem's range \[0, 1e\+12\]"):
        load(AorConfig, "tiny", None, [f"{key}=1e13"])
    assert load(AorConfig, "tiny", None, [f"{key}=1e12"]).params.effects["cohesion_sjkr"]["cohesion_energy_density"] == 1e12
    with pytest.raises(SpecError, match="outside libdem's range"):
        CampaignSpec(rig="aor", preset="tiny", ranges={"friction": (0.2, 0.8), key: (0.0, 1e13)})
    CampaignSpec(rig="aor", preset="tiny", ranges={"friction": (0.2, 0.8), key: (0.0, 1e12)})
