"""
Sphinx extension: a hand-drawn picture of the package's folders, checked against the package.

Usage in an RST page::

    .. gongsynth-layout::

       gongsynth/
       ├── sun/
       │   ├── stokes.py   ...

The content is rendered as a literal block.  At build time every module and
sub-package of the installed ``gongsynth`` must appear in the picture (by its
file or folder name, under the right parent folder), and every ``*.py`` file or
``folder/`` the picture names must exist; a mismatch is a build error, so the
picture cannot drift from the folders.
"""
import re
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive

__all__ = ["check_layout", "package_entries", "setup"]

_NAME = re.compile(r"([A-Za-z_][A-Za-z0-9_]*(?:\.py|/))")
_TREE = re.compile(r"[├└│─\s]+")  # tree-drawing prefix of a line


def package_entries(root):
    """
    The folders and modules of a package, as paths relative to its parent.

    Parameters
    ----------
    root : `pathlib.Path`
        The package folder (the one holding ``__init__.py``).

    Returns
    -------
    set of str
        ``"gongsynth/"``, ``"gongsynth/sun/"``, ``"gongsynth/sun/stokes.py"``, ...
        (``__init__.py``, the generated ``_version.py`` and caches left out).
    """
    entries = {root.name + "/"}
    for path in root.rglob("*"):
        relative = path.relative_to(root.parent)
        if "__pycache__" in relative.parts or path.name == "_version.py":  # written by setuptools_scm
            continue
        if path.is_dir() and (path / "__init__.py").exists():
            entries.add(relative.as_posix() + "/")
        elif path.suffix == ".py" and path.name != "__init__.py":
            entries.add(relative.as_posix())
    return entries


def picture_entries(text):
    """
    The folders and modules a tree picture names, with their full paths.

    A line's indentation (its tree-drawing prefix, four characters a level)
    gives its depth; a folder named at the start of a line opens that level,
    and further ``*.py`` names on the same line belong to the same folder as
    the line's first name.  Text after two spaces of the names (the notes) is
    ignored.

    Parameters
    ----------
    text : str

    Returns
    -------
    set of str
    """
    entries, stack = set(), []
    for line in text.splitlines():
        prefix = _TREE.match(line)
        start = prefix.end() if prefix else 0
        body = line[start:]
        names_part = re.split(r"\s{3,}", body.strip(), maxsplit=1)[0] if body.strip() else ""
        names = _NAME.findall(names_part)
        if not names:
            continue
        depth = start // 4
        del stack[depth:]
        parent = "".join(stack)
        for name in names:
            entries.add(parent + name)
        if names[0].endswith("/") and len(names) == 1:
            stack.append(names[0])
    return entries


def check_layout(text, root):
    """
    Compare a tree picture with the package folder.

    Parameters
    ----------
    text : str
        The picture.
    root : `pathlib.Path`
        The package folder.

    Returns
    -------
    missing, unknown : list of str
        Package entries the picture leaves out; picture entries the package lacks.
    """
    real, drawn = package_entries(root), picture_entries(text)
    return sorted(real - drawn), sorted(drawn - real)


class Layout(Directive):
    has_content = True

    def run(self):
        import gongsynth

        root = Path(gongsynth.__file__).parent
        text = "\n".join(self.content)
        missing, unknown = check_layout(text, root)
        if missing or unknown:
            raise self.error(
                "the layout picture does not match the package: "
                f"not drawn {missing or 'none'}; drawn but absent {unknown or 'none'}")
        env = self.state.document.settings.env
        for path in sorted(root.rglob("*.py")):
            env.note_dependency(str(path))
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        return [block]


def setup(app):
    app.add_directive("gongsynth-layout", Layout)
    return {"version": "1.0", "parallel_read_safe": True, "parallel_write_safe": True}
