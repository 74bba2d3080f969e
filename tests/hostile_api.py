"""Hostile arguments for the package's public functions, run in a process of its own.

``python hostile_api.py [SECONDS]``: a valid call of each function in a module's
``__all__`` (outside the private ``_runtime`` and ``_kernels`` and the command line) is
recorded from its own docstring's examples; then each argument is spoilt in turn and the
call made again in a forked child killed past SECONDS (:func:`hostile_calls.forked`).
Numbers (an int or a float in the recorded call) get -1, 2**62 and NaN; the arguments of
the package's top-level functions also get a word, None, an object, an empty array and a
complex number. Prints ``CASE name parameter value`` then ``RESULT <outcome>``; ``DONE``.
"""

from __future__ import annotations

import copy
import doctest
import importlib
import inspect
import numbers
import os
import pkgutil
import sys
import tempfile

import numpy as np
from doctest_namespace import shared
from hostile_calls import forked

NUMBERS = {"-1": -1, "2**62": 2**62, "nan": float("nan")}
OTHERS = {"word": "x", "None": None, "object": object(), "empty": np.array([]),
          "complex": 1 + 1j}


def public_functions() -> dict:
    """{code object: (dotted name, function)} of every function a module names in
    ``__all__`` (defined there)."""
    import superfacets

    out = {}
    for m in pkgutil.walk_packages(superfacets.__path__, "superfacets."):
        if any(p in m.name for p in (".cli", "._kernels", "._runtime", "__main__")):
            continue
        mod = importlib.import_module(m.name)
        for a in getattr(mod, "__all__", []):
            fn = getattr(mod, a, None)
            if inspect.isfunction(fn) and fn.__module__ == m.name:
                out[fn.__code__] = (f"{m.name}.{a}", fn)
    return out


def recorded_calls(functions: dict) -> dict:
    """{name: (function, {parameter: value})}: the first call of each function made while
    its docstring's examples run (in a temporary folder)."""
    calls: dict = {}

    def profile(frame, event, arg):
        if event == "call" and frame.f_code in functions:
            name, fn = functions[frame.f_code]
            if name not in calls:
                try:
                    calls[name] = (fn, _arguments(fn, frame.f_locals))
                except Exception:  # noqa: BLE001 (a value that cannot be copied: no case)
                    pass

    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    os.chdir(tempfile.mkdtemp())
    for name, fn in functions.values():
        mod = sys.modules[fn.__module__]
        for test in finder.find(fn, name, module=mod, globs={**shared(), **vars(mod)}):
            sys.setprofile(profile)
            try:
                runner.run(test, out=lambda s: None)
            finally:
                sys.setprofile(None)
    return calls


def _arguments(fn, local: dict) -> dict:
    """The call's arguments by name (``**options`` spread; ``*args`` refused)."""
    out = {}
    for p in inspect.signature(fn).parameters.values():
        if p.kind == p.VAR_POSITIONAL:
            raise TypeError("*args")
        if p.kind == p.VAR_KEYWORD:
            out.update({k: copy.copy(v) for k, v in local.get(p.name, {}).items()})
        elif p.name in local:
            out[p.name] = copy.copy(local[p.name])
    return out


def cases(calls: dict, top: set):
    """(name, parameter, value's name, value) of every spoilt call."""
    for name in sorted(calls):
        _, kwargs = calls[name]
        for p, v in kwargs.items():
            if isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)):
                yield from ((name, p, k, x) for k, x in NUMBERS.items())
            if name in top:
                yield from ((name, p, k, x) for k, x in OTHERS.items())


def main(limit: float) -> None:
    import superfacets

    functions = public_functions()
    calls = recorded_calls(functions)
    print("RECORDED", len(calls), "of", len(functions), flush=True)
    top = {f"{fn.__module__}.{fn.__name__}" for fn in map(superfacets.__dict__.get,
                                                           superfacets.__all__)
           if inspect.isfunction(fn)}
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 2)  # (progress bars of the runs that go through)
    for name, p, shown, value in cases(calls, top):
        fn, kwargs = calls[name]
        print("CASE", name, p, shown, flush=True)
        outcome = forked(lambda: fn(**{**kwargs, p: value}), limit)
        print("RESULT", outcome, flush=True)
    print("DONE", flush=True)


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 20.0)
