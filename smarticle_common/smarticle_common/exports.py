"""Lazy public names of a package: ``__all__`` resolved from its modules on first use (no rclpy import).

Each package's ``__init__`` lists its public names with the module that defines each, and lets this
module build the package's ``__getattr__`` (PEP 562), so importing a package stays cheap while
``from smarticle_sim import Physics`` still works::

    _EXPORTS = {'Physics': 'physics', 'SimError': 'errors'}
    __all__ = sorted(_EXPORTS)
    __getattr__ = lazy_getattr(__name__, _EXPORTS)
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping

__all__ = ['lazy_getattr']


def lazy_getattr(package: str, exports: Mapping[str, str]) -> Callable[[str], object]:
    """The module ``__getattr__`` of ``package``: a name of ``exports`` imported from its module on first use."""
    def __getattr__(name: str) -> object:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f'module {package!r} has no attribute {name!r}')
        return getattr(importlib.import_module(f'.{module}', package), name)
    return __getattr__
