"""Every `hems` verb's --help renders and reads as written (no argparse escapes left in it)."""

from __future__ import annotations

import argparse

from hems_ros.cli.main import build_parser


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
    assert "Kp (%/um)" in helps["hems tune"] and "weight of MACSI (% per" in helps["hems tune"].replace("\n", " ")
