"""
Sphinx extension: the ``gongsynth`` command line's help and default configuration,
generated from the code at build time so the pages cannot drift from it.

Directives::

    .. gongsynth-cli-help::
       :command: simulate          (omit for the top-level help)

    .. gongsynth-default-config::  (the output of ``gongsynth config --print-defaults``)
"""
import argparse
import contextlib
import io

from docutils import nodes
from docutils.parsers.rst import Directive, directives

__all__ = ["cli_help", "default_config", "setup"]


def cli_help(command=None):
    """
    The ``--help`` text of ``gongsynth`` or of one of its sub-commands.

    Parameters
    ----------
    command : str, optional
        Sub-command name; ``None`` for the top level.

    Returns
    -------
    str
    """
    from gongsynth.cli import build_parser

    parser = build_parser()
    if command is not None:
        subparsers = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        choices = subparsers[0].choices if subparsers else {}
        if command not in choices:
            raise ValueError(f"gongsynth has no sub-command {command!r}; known: {sorted(choices)}")
        parser = choices[command]
    # A fixed width keeps the page independent of the terminal that builds it.
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=88)
    return parser.format_help()


def default_config():
    """The text that ``gongsynth config --print-defaults`` prints (str)."""
    from gongsynth.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(["config", "--print-defaults"])
    if status not in (0, None):
        raise RuntimeError(f"'gongsynth config --print-defaults' exited with {status}")
    return out.getvalue()


def _depend_on_cli(directive):
    """Re-read the page whenever the CLI or the configuration code changes."""
    import inspect

    from gongsynth import cli, config, instrument
    env = directive.state.document.settings.env
    for module in (cli, config, instrument):
        env.note_dependency(inspect.getsourcefile(module))


def _literal(text, language):
    block = nodes.literal_block(text, text)
    block["language"] = language
    return block


class CliHelp(Directive):
    has_content = False
    option_spec = {"command": directives.unchanged}

    def run(self):
        command = self.options.get("command")
        try:
            text = cli_help(command)
        except ValueError as exc:
            raise self.error(str(exc))
        _depend_on_cli(self)
        prompt = "$ gongsynth " + (f"{command} " if command else "") + "--help\n"
        return [_literal(prompt + text, "text")]


class DefaultConfig(Directive):
    has_content = False

    def run(self):
        _depend_on_cli(self)
        return [_literal(default_config(), "toml")]


def setup(app):
    app.add_directive("gongsynth-cli-help", CliHelp)
    app.add_directive("gongsynth-default-config", DefaultConfig)
    return {"version": "1.0", "parallel_read_safe": True, "parallel_write_safe": True}
