"""Options shared by every command: ``--res`` means HxW everywhere, one ``--set`` parser, defaults from the settings."""

import click
import pytest

from roomlight.cli.common import RESOLUTION, default_of, parse_sets
from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError
from roomlight.fitting.inverse import FitConfig, fit_config


def test_res_is_height_by_width_and_a_single_number_is_square():
    assert RESOLUTION.convert("128x256", None, None) == (128, 256)
    assert RESOLUTION.convert("96", None, None) == (96, 96)
    assert RESOLUTION.convert((4, 8), None, None) == (4, 8)
    for bad in ("0x5", "axb", "1x2x3", "-4"):
        with pytest.raises(click.BadParameter):
            RESOLUTION.convert(bad, None, None)


def test_set_values_parse_as_json_then_yaml_then_text_and_nest_on_dots():
    got = parse_sets(["lr=1e-4", "direct_resolution=[64, 128]", "flag=True", "image=hdr", "loss.peak=0",
                      "eval-every=5"])
    assert got == {"lr": 1e-4, "direct_resolution": [64, 128], "flag": True, "image": "hdr", "loss": {"peak": 0},
                   "eval_every": 5}
    with pytest.raises(click.ClickException):
        parse_sets(["no-equals-sign"])


def test_fit_config_is_strict_and_round_trips_through_json_types():
    cfg = fit_config("fast", iterations=3, direct_resolution=[8, 16])
    assert cfg.direct_resolution == (8, 16)  # lists from --set / JSON become tuples again
    assert isinstance(cfg, StrictConfig)
    assert FitConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(RoomlightError, match="unknown field"):
        fit_config("paper", iteration=3)


def test_help_defaults_come_from_the_settings_class():
    assert default_of(FitConfig, "margin") == f"[default: {FitConfig.margin}]"
    assert default_of(FitConfig, "direct_resolution") == "[default: 128x256]"
