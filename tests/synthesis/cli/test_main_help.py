"""Every subcommand's help text reads as written (no argparse escapes left)."""

import argparse

import pytest

from synthesis.cli import build_parser


def _subparsers(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def test_there_are_subcommands():
    assert {"synthesize", "yield", "analyze"} <= set(_subparsers(build_parser()))


@pytest.mark.parametrize("name", sorted(_subparsers(build_parser())))
def test_help_has_no_escaped_percent(name):
    text = _subparsers(build_parser())[name].format_help()
    assert "%%" not in text, text
