"""Build of the compiled kernels (``superfacets._kernels._cxx``, C++ through pybind11).

Everything else about the package is in ``pyproject.toml``. The extension is optional:
where it cannot be built (no C++ compiler), the install goes on and the numba kernels
run instead (they compile on first use). ``-ffp-contract=off``: no fused multiply-adds,
so that every floating-point operation rounds as numba's do (tested bit for bit).
"""

import hashlib
from glob import glob

from pybind11.setup_helpers import ParallelCompile, Pybind11Extension, build_ext
from setuptools import setup

ParallelCompile("NPY_NUM_BUILD_JOBS").install()  # the source files on every core

SOURCES = sorted(glob("src/superfacets/_kernels/cxx/*.cpp"))
HEADERS = sorted(glob("src/superfacets/_kernels/cxx/*.hpp"))
# the digest of the sources, built into the module: tests/test_native.py tells a module
# built from older sources (an editable install not rebuilt) from a current one
digest = hashlib.sha256()
for path in SOURCES + HEADERS:
    with open(path, "rb") as f:
        digest.update(path.rsplit("/", 1)[-1].encode() + b"\0" + f.read())

cxx = Pybind11Extension(
    "superfacets._kernels._cxx",
    SOURCES,
    depends=HEADERS,
    define_macros=[("SFK_SOURCES", f'"{digest.hexdigest()}"')],
    cxx_std=17,
    extra_compile_args=["-O2", "-ffp-contract=off", "-fno-math-errno"],
    optional=True,
)

setup(ext_modules=[cxx], cmdclass={"build_ext": build_ext})
