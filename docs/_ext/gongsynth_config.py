"""
Sphinx extension: the default run configuration, generated from the code at build time.

Directive::

    .. gongsynth-default-config::  (the output of ``gongsynth config --print-defaults``)

The command line's help pages come from sphinx-argparse (``.. argparse::``).
"""
import contextlib
import io

from docutils import nodes
from docutils.parsers.rst import Directive

__all__ = ["default_config", "setup"]


def default_config():
    """The text that ``gongsynth config --print-defaults`` prints (str)."""
    from gongsynth.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(["config", "--print-defaults"])
    if status not in (0, None):
        raise RuntimeError(f"'gongsynth config --print-defaults' exited with {status}")
    return out.getvalue()


class DefaultConfig(Directive):
    has_content = False

    def run(self):
        import inspect

        from gongsynth import cli, config, instrument

        # Re-read the page whenever the CLI or the configuration code changes.
        env = self.state.document.settings.env
        for module in (cli, config, instrument):
            env.note_dependency(inspect.getsourcefile(module))
        text = default_config()
        block = nodes.literal_block(text, text)
        block["language"] = "toml"
        return [block]


def setup(app):
    app.add_directive("gongsynth-default-config", DefaultConfig)
    return {"version": "1.0", "parallel_read_safe": True, "parallel_write_safe": True}
