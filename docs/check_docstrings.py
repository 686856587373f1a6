"""
Check the docstrings of gongsynth's public API against the project's standard.

Every public function (a name in a module's ``__all__``) must have a numpydoc
``Parameters`` section when it takes arguments, a ``Returns`` (or ``Yields``)
section when it returns a value, and an ``Examples`` section with at least one
``>>>`` line (run as a doctest by the test suite).  Public classes need
``Parameters`` (or ``Attributes``) and ``Examples`` (exceptions need no
example); their public methods and
properties need ``Parameters``/``Returns`` like functions (no example
required).

Usage::

    python docs/check_docstrings.py          # list every gap, exit 1 if any
    python docs/check_docstrings.py --summary
"""
import argparse
import ast
import importlib
import inspect
import pkgutil
import re
import sys
import textwrap

__all__ = ["public_modules", "check_object", "gaps", "main"]

_SECTION = re.compile(r"^\s*(\w[\w ]*)\n\s*-{3,}\s*$", re.MULTILINE)


def public_modules(package="gongsynth"):
    """
    The package and its modules that declare ``__all__`` (private ones skipped).

    Returns
    -------
    list of module
    """
    root = importlib.import_module(package)
    modules = [root]
    for info in pkgutil.walk_packages(root.__path__, prefix=package + "."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        module = importlib.import_module(info.name)
        if hasattr(module, "__all__"):
            modules.append(module)
    return modules


def _sections(doc):
    return {m.group(1).strip() for m in _SECTION.finditer(doc or "")}


def _returns_value(func):
    """Whether the function's source returns something other than None."""
    try:
        source = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return True
    tree = ast.parse(source)
    body = tree.body[0]
    for node in ast.walk(body):
        if isinstance(node, (ast.Return,)) and node.value is not None:
            if not (isinstance(node.value, ast.Constant) and node.value.value is None):
                return True
        if isinstance(node, (ast.Yield, ast.YieldFrom)):
            return True
    return False


def _takes_arguments(func):
    try:
        params = inspect.signature(func).parameters
    except (TypeError, ValueError):
        return False
    return any(name not in ("self", "cls") for name in params)


def check_object(obj, *, need_example):
    """
    The standard's missing pieces for one function, method or class.

    Parameters
    ----------
    obj : function, method, property or class
    need_example : bool
        Whether an ``Examples`` section with ``>>>`` is required.

    Returns
    -------
    list of str
        Missing items, e.g. ``["Parameters", "Examples"]``; empty if complete.
    """
    doc = inspect.getdoc(obj) if not isinstance(obj, property) else obj.__doc__
    if not doc:
        return ["docstring"]
    sections = _sections(doc)
    missing = []
    if inspect.isclass(obj):
        init = obj.__dict__.get("__init__")
        has_fields = bool(getattr(obj, "__dataclass_fields__", None))
        if (has_fields or (init is not None and _takes_arguments(init))) and not (
                sections & {"Parameters", "Attributes"}):
            missing.append("Parameters/Attributes")
    elif isinstance(obj, property):
        pass  # a property's docstring says what it is; its type and unit are checked by eye
    else:
        if _takes_arguments(obj) and "Parameters" not in sections:
            missing.append("Parameters")
        if _returns_value(obj) and not sections & {"Returns", "Yields"}:
            missing.append("Returns")
    if need_example and ("Examples" not in sections or ">>>" not in doc):
        missing.append("Examples")
    return missing


def gaps(package="gongsynth"):
    """
    Every gap in the public API, as (qualified name, missing items).

    Returns
    -------
    list of tuple
    """
    found, seen = [], set()
    for module in public_modules(package):
        for name in module.__all__:
            obj = getattr(module, name, None)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            home = f"{obj.__module__}.{obj.__qualname__}"
            if home in seen:
                continue
            seen.add(home)
            is_exception = inspect.isclass(obj) and issubclass(obj, BaseException)
            missing = check_object(obj, need_example=not is_exception)
            if missing:
                found.append((home, missing))
            if inspect.isclass(obj) and not issubclass(obj, BaseException):
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    target = member.__func__ if isinstance(member, (classmethod, staticmethod)) \
                        else member
                    if not (inspect.isfunction(target) or isinstance(target, property)):
                        continue
                    missing = check_object(target, need_example=False)
                    if missing:
                        found.append((f"{home}.{attr}", missing))
    return found


def main(argv=None):
    """Print the gaps; exit status 1 if there are any."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--summary", action="store_true", help="counts per missing item only")
    args = parser.parse_args(argv)
    found = gaps()
    if args.summary:
        counts = {}
        for _, missing in found:
            for item in missing:
                counts[item] = counts.get(item, 0) + 1
        for item, n in sorted(counts.items()):
            print(f"{item:24s} {n}")
    else:
        for name, missing in found:
            print(f"{name}: missing {', '.join(missing)}")
    print(f"{len(found)} public object(s) with gaps")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
