"""cogniframe: one parameter file in, a buildable CogniFly exoskeleton out.

Stages, data flowing one way: spec -> frame -> partlist -> parts -> export -> analysis -> report.
Importing this package has no side effects and does not import CadQuery (nor pydantic or numpy):
the Python API (`load`, `Design`, `CheckResult`, `BuildResult`, `ParamsError`, `sweep`;
docs/api.md) is looked up on first use.

`cogniframe.sweep` is both the package of the design-space sweeps (cogniframe/sweep/) and the
API call `cogniframe.sweep(sweep_file_or_dict, scheduler=None) -> pandas.DataFrame`: the package
module is made callable when it is first reached through this attribute.
"""

import sys as _sys
import types as _types

from .version import __version__

__all__ = ["BuildResult", "CheckResult", "Design", "ParamsError", "UserError", "__version__", "load", "sweep"]

_API = {"load": "api", "Design": "api", "CheckResult": "api", "BuildResult": "api", "ParamsError": "api",
        "UserError": "errors"}


def __getattr__(name: str):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'cogniframe' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


class _CallableSweep(_types.ModuleType):
    """The cogniframe.sweep package, callable as the API's `sweep`."""

    def __call__(self, sweep_file_or_dict, scheduler=None, **options):
        from .api import sweep

        return sweep(sweep_file_or_dict, scheduler, **options)


class _Package(_types.ModuleType):
    """This package's module type: its `sweep` attribute is the sweep package made callable.
    (Python binds a subpackage to its parent's attribute when it is imported; a plain function of
    that name would be replaced by the module, so the module itself takes the call.)"""

    @property
    def sweep(self):
        from importlib import import_module

        module = import_module(f"{__name__}.sweep")  # its __init__ is a docstring: nothing heavy
        if not isinstance(module, _CallableSweep):
            module.__class__ = _CallableSweep
        return module

    @sweep.setter
    def sweep(self, module):  # the import system binding the subpackage: `sweep` already reaches it
        pass


_sys.modules[__name__].__class__ = _Package
