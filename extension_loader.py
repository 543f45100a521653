"""Load this working tree as the ``monoskel`` package without installing it.

Used by ``batch.py`` (which must run both inside Blender and as plain
``python batch.py`` with the PyPI ``bpy`` module) and by the test-suite, so
that the code under test is the code in the checkout.  Importing this module
does not import ``bpy``.
"""

from __future__ import annotations

import importlib.util
import os
import sys

PACKAGE = "monoskel"
ROOT = os.path.dirname(os.path.abspath(__file__))


def load_extension(package: str = PACKAGE):
    """Import the repository root as package ``package`` (idempotent) and return it."""
    if package in sys.modules:
        return sys.modules[package]
    spec = importlib.util.spec_from_file_location(
        package, os.path.join(ROOT, "__init__.py"), submodule_search_locations=[ROOT]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[package] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[package]
        raise
    return module
