"""Build of the compiled kernels (``superfacets._kernels._cxx``, C++ through pybind11).

Everything else about the package is in ``pyproject.toml``. The extension is optional:
where it cannot be built (no C++ compiler), the install goes on and the numba kernels
run instead (they compile on first use). ``-ffp-contract=off``: no fused multiply-adds,
so that every floating-point operation rounds as numba's do (tested bit for bit).
"""

from glob import glob

from pybind11.setup_helpers import ParallelCompile, Pybind11Extension, build_ext
from setuptools import setup

ParallelCompile("NPY_NUM_BUILD_JOBS").install()  # the source files on every core

cxx = Pybind11Extension(
    "superfacets._kernels._cxx",
    sorted(glob("src/superfacets/_kernels/cxx/*.cpp")),
    depends=sorted(glob("src/superfacets/_kernels/cxx/*.hpp")),
    cxx_std=17,
    extra_compile_args=["-O2", "-ffp-contract=off", "-fno-math-errno"],
    optional=True,
)

setup(ext_modules=[cxx], cmdclass={"build_ext": build_ext})
