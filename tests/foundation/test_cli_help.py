"""Every `hems` verb's --help renders and reads as written (no argparse escapes left in it), and
every numeric option checks its value before the verb starts anything."""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hems_ros.cli import numbers
from hems_ros.cli.main import build_parser

NUMBER_TYPES = {
    numbers.finite,
    numbers.positive,
    numbers.non_negative,
    numbers.positive_int,
    numbers.non_negative_int,
    numbers.positive_or_max,
}
REFERENCE_BAG = Path(__file__).resolve().parents[2] / "bags" / "demo_grasp_index"


def all_parsers(parser: argparse.ArgumentParser, path: str = "hems"):
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from all_parsers(sub, f"{path} {name}")


def test_every_help_renders_without_escaped_percent_signs():
    helps = dict((path, parser.format_help()) for path, parser in all_parsers(build_parser()))
    assert {"hems tune", "hems status", "hems bag export", "hems up"} <= helps.keys()
    for path, text in helps.items():
        # a description is printed as written, so '%%' there shows up doubled
        assert "%%" not in text, f"{path} --help shows '%%'"
        assert text.startswith("usage: " + path)
    assert "Kp (%/um)" in helps["hems tune"] and "weight of MACSI (% per" in helps[
        "hems tune"
    ].replace("\n", " ")


def _numeric(action: argparse.Action) -> bool:
    if action.type in (int, float):
        return True
    default = action.const if action.default is None else action.default
    return isinstance(default, (int, float)) and not isinstance(default, bool)


def test_every_numeric_option_checks_its_value():
    checked = []
    for path, parser in all_parsers(build_parser()):
        for action in parser._actions:
            if _numeric(action) or action.type in NUMBER_TYPES:
                assert (
                    action.type in NUMBER_TYPES
                ), f"{path} {action.option_strings}: type {action.type}"
                checked.append(f"{path} {action.option_strings[0]}")
    assert {
        "hems replay --rate",
        "hems ping --count",
        "hems tune --max-evaluations",
        "hems up --duration",
        "hems grasp --hold-s",
        "hems demo --ready-timeout",
        "hems record --chunk-size",
    } <= set(checked)


@pytest.mark.parametrize(
    "parse, text, message",
    [
        (numbers.positive, "nan", "'nan': must be a finite number > 0"),
        (numbers.positive_or_max, "fast", "'fast' is not a number"),
        (numbers.positive, "inf", "'inf': must be a finite number > 0"),
        (numbers.positive, "0", "'0': must be a finite number > 0"),
        (numbers.non_negative, "-1", "'-1': must be a finite number >= 0"),
        (numbers.finite, "-inf", "'-inf': must be a finite number"),
        (numbers.finite, "ten", "'ten' is not a number"),
        (numbers.positive_int, "1.5", "'1.5' is not a whole number"),
        (numbers.positive_int, "0", "'0': must be a whole number > 0"),
        (numbers.non_negative_int, "-1", "'-1': must be a whole number >= 0"),
    ],
)
def test_bad_numbers_are_named(parse, text, message):
    with pytest.raises(argparse.ArgumentTypeError) as info:
        parse(text)
    assert str(info.value) == message


def test_good_numbers_pass():
    assert numbers.positive("2.5") == 2.5 and numbers.non_negative("0") == 0.0
    assert numbers.finite("-3") == -3.0 and numbers.positive_int("7") == 7


def test_replay_refuses_a_nan_rate_at_once():
    # A NaN rate had put every message due at NaN seconds: replay spun forever, deaf to SIGTERM.
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "hems_ros.cli.main", "replay", str(REFERENCE_BAG), "--rate", "nan"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert "argument --rate: 'nan': must be a finite number > 0" in done.stderr
    assert time.monotonic() - started < 30


@pytest.mark.parametrize(
    "keyword, value, message",
    [
        ("rate", float("nan"), "rate must be a finite number > 0, not nan"),
        ("clock_hz", -5.0, "clock_hz must be a finite number >= 0, not -5.0"),
        ("start_delay", -1.0, "start_delay must be a finite number >= 0, not -1.0"),
    ],
)
def test_replay_api_refuses_bad_numbers(keyword, value, message):
    from hems_ros.cli.replay import replay

    with pytest.raises(ValueError, match=message):
        replay(REFERENCE_BAG, **{keyword: value})


@pytest.mark.parametrize(
    "argv, code, message",
    [
        (
            ["step", "--physics-config", "nonexistent"],
            2,
            "step: no parameter set named 'nonexistent'",
        ),
        (["demo", "--plot", "{file}/grasp.png"], 1, "hems demo: [Errno 17] File exists"),
        (
            ["experiment", "ch6", "-o", "{file}/out"],
            1,
            "hems experiment: [Errno 20] Not a directory",
        ),
        (
            ["up", "--record", "{file}/bag", "--duration", "1"],
            2,
            "hems up: --record {file}/bag: cannot make {file}",
        ),
        (["demo", "--record", "{file}/bag"], 2, "demo: --record {file}/bag: cannot make {file}"),
        (
            ["replay", str(REFERENCE_BAG), "--topic", "/hems/nope"],
            2,
            "on the selected topics; its topics: /diagnostics, /hems/index/controller_status",
        ),
        (
            ["up", "--extra-params", "{file}/tuned.yaml"],
            2,
            "hems up: --extra-params {file}/tuned.yaml: no such file",
        ),
        (["tune", "--write-params", "{file}/tuned.yaml"], 1, "hems tune: [Errno 17] File exists"),
        (
            ["grasp", "--fingers", "index,pinky"],
            2,
            "grasp: unknown finger 'pinky': expected one of thumb_flexion, thumb_abduction",
        ),
    ],
)
def test_bad_inputs_stop_before_anything_starts(tmp_path, argv, code, message):
    # each is refused before the graph or the runs start (and a replay of a missing topic does not
    # replay nothing and exit 0)
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    argv = [a.format(file=blocker) for a in argv]
    message = message.format(file=blocker)
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "hems_ros.cli.main", *argv],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert done.returncode == code, done.stderr
    assert message in done.stderr
    assert "Traceback" not in done.stderr
    assert time.monotonic() - started < 20
    assert not (tmp_path / "bags").exists()


def test_finding_the_verbs_loads_no_numerical_library() -> None:
    """Every `hems` command builds the whole parser first; a `hems setpoint` that joins a
    running graph should not spend seconds of the host's CPU importing what only the diagnosis
    and the plots use."""
    code = (
        "import sys; from hems_ros.cli.main import build_parser; build_parser(); "
        "print(sorted({m.split('.')[0] for m in sys.modules} & "
        "{'scipy', 'numba', 'matplotlib', 'dask', 'distributed'}))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"
