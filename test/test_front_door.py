"""
The package's front door: ``from hydro_sdp import ...`` and its docstrings.

The user-level names are imported on first use; each has a numpydoc docstring whose
Parameters are the function's own (checked for every public function and class of the
package, not only these), with See Also and Examples, and the Examples run.
"""

import dataclasses
import doctest
import importlib
import inspect
import pkgutil
import re
import shutil
import subprocess
import sys

from conftest import REPO
import hydro_sdp
import pytest

#: The user-level names (the README's "In Python" uses them).
FRONT = [name for name in hydro_sdp.__all__ if not name.startswith('__')]


def test_import_is_cheap_and_names_resolve_on_first_use():
    loaded = subprocess.run(
        [sys.executable, '-c', 'import sys, hydro_sdp; print(sorted(m for m in sys.modules '
         'if m.split(".")[0] in ("numpy", "scipy", "yaml", "rclpy", "hydro_sdp")))'],
        capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == "['hydro_sdp']"
    for name in FRONT:
        value = getattr(hydro_sdp, name)
        assert value is getattr(importlib.import_module(value.__module__), name)
        assert name in dir(hydro_sdp)
    with pytest.raises(AttributeError, match='no attribute'):
        hydro_sdp.identifyy


def _section(doc, title):
    """Return the lines of a numpydoc section, or None."""
    match = re.search(rf'^{title}\n-+\n(.*?)(?=^\S[^\n]*\n-+\n|\Z)', doc, re.M | re.S)
    return None if match is None else match.group(1)


def documented_parameters(doc):
    """Name groups of a docstring's Parameters section (``a, b : float`` is one group)."""
    section = _section(inspect.cleandoc(doc), 'Parameters')
    if section is None:
        return None
    names = []
    for line in section.splitlines():
        if line and not line[0].isspace():
            names.append([n.strip().lstrip('*') for n in line.split(' : ')[0].split(',')])
    return names


def signature_parameters(obj):
    if inspect.isclass(obj):
        if dataclasses.is_dataclass(obj):
            return [f.name for f in dataclasses.fields(obj) if f.init]
        if hasattr(obj, '_fields'):  # a NamedTuple
            return list(obj._fields)
        obj = obj.__init__
    try:
        parameters = inspect.signature(obj).parameters.values()
    except (TypeError, ValueError):
        return None
    return [p.name for p in parameters if p.name not in ('self', 'cls')]


def public_callables():
    """Every public function and class defined in the package, by qualified name."""
    for info in pkgutil.walk_packages(hydro_sdp.__path__, 'hydro_sdp.'):
        if '.ros' in info.name or info.name.endswith('__main__'):
            continue  # the nodes' modules import rclpy; their parameters are tables
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if (not name.startswith('_') and (inspect.isfunction(obj) or inspect.isclass(obj))
                    and obj.__module__ == module.__name__):
                yield f'{info.name}.{name}', obj


def test_docstrings_name_the_parameters_the_signature_takes():
    wrong = []
    for where, obj in public_callables():
        documented = documented_parameters(obj.__doc__ or '')
        actual = signature_parameters(obj)
        if documented is None or actual is None:
            continue
        flat = [name for group in documented for name in group]
        # In order, but names documented together (``vn, vp : float``) may stand apart.
        in_order = flat == actual if all(len(g) == 1 for g in documented) else \
            sorted(flat) == sorted(actual)
        if not in_order:
            wrong.append(f'{where}: documented {documented}, takes {actual}')
    assert not wrong, '\n'.join(wrong)


@pytest.mark.parametrize('name', FRONT)
def test_the_front_door_is_documented_with_see_also_and_examples(name):
    doc = inspect.cleandoc(getattr(hydro_sdp, name).__doc__)
    assert _section(doc, 'See Also'), f'{name}: no See Also'
    if name != 'save_controller':  # load_controller's example writes and reads one
        assert _section(doc, 'Examples'), f'{name}: no Examples'


def test_the_examples_run(tmp_path, monkeypatch):
    shutil.copytree(REPO / 'config', tmp_path / 'config')
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    attempted = 0
    for name in FRONT:
        found = doctest.DocTestFinder(recurse=False).find(getattr(hydro_sdp, name), name, globs={})
        for test in found:
            runner.run(test)
            attempted += len(test.examples)
    failed, _ = runner.summarize(verbose=False)
    assert failed == 0 and attempted > 30


def test_all_lists_every_export():
    assert sorted(FRONT) == sorted(hydro_sdp._EXPORTS)
