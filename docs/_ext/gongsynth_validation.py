"""
Sphinx extension: the validation table, measured while the documentation builds.

``.. gongsynth-validation-table::`` runs every row of ``docs/validation_numbers.py``
and renders quantity, expected value, the value measured now and the commands
that reproduce it.  A row whose test does not exist in ``tests/`` is a build
warning (an error under ``-W``), so the page cannot point at a test that was
renamed or removed.  The page is rebuilt on every build.
"""
import ast
import sys
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.nodes import nested_parse_with_titles

__all__ = ["test_exists", "setup"]

DOCS = Path(__file__).resolve().parents[1]
REPO = DOCS.parent
logger = logging.getLogger(__name__)


def test_exists(node_id):
    """
    Whether a pytest node id ``path::function`` names a test function in the tree.

    Parameters
    ----------
    node_id : str

    Returns
    -------
    bool
    """
    path, _, name = node_id.partition("::")
    name = name.split("[")[0]
    file = REPO / path
    if not file.is_file():
        return False
    tree = ast.parse(file.read_text())
    return any(isinstance(n, ast.FunctionDef) and n.name == name for n in ast.walk(tree))


def _validation_numbers():
    if str(DOCS) not in sys.path:
        sys.path.insert(0, str(DOCS))
    import validation_numbers
    return validation_numbers


class ValidationTable(Directive):
    has_content = False

    def run(self):
        module = _validation_numbers()
        lines = [".. list-table::", "   :header-rows: 1", "   :widths: 20 22 28 30",
                 "   :class: gongsynth-validation", "",
                 "   * - Quantity", "     - Expected (source)", "     - Measured in this build",
                 "     - Reproduce"]
        total = 0.0
        for row in module.ROWS:
            if not test_exists(row.test):
                logger.warning(f"validation row {row.key!r}: test {row.test} not found",
                               location=(self.state.document.settings.env.docname, self.lineno))
            text, seconds = module.measure(row)
            text = text.replace("|", "\\|")  # |x| is a magnitude, not an RST substitution
            total += seconds
            lines += [f"   * - {row.quantity}", f"     - {row.expected}", f"     - {text}",
                      f"     - ``{row.command}``", "",
                      f"       ``python docs/validation_numbers.py {row.key}``"]
        logger.info(f"validation table: {len(module.ROWS)} rows measured in {total:.1f} s")
        container = nodes.container()
        nested_parse_with_titles(self.state, StringList(lines, source="gongsynth-validation"),
                                 container)
        return container.children


def _always_outdated(app, env, added, changed, removed):
    """The measured numbers depend on the whole package: re-read the page every build."""
    return [docname for docname in env.found_docs if docname == "validation"]


def setup(app):
    app.add_directive("gongsynth-validation-table", ValidationTable)
    app.connect("env-get-outdated", _always_outdated)
    return {"version": "1.0", "parallel_read_safe": True, "parallel_write_safe": True}
