#!/usr/bin/env bash
# Install a built wheel with no extras into a fresh virtual environment, with no C++
# compiler on the PATH (the wheel carries the compiled kernels), and check that the demo
# and the core commands work there and that the others name the extra to install.
# Usage: tools/check_wheel.sh DIST [MESH]   (DIST: the folder of `make wheel`)
# MESH: default the bunny of ../shared beside the repository, else the demo's mesh.
# Prints the install's time and the environment's size at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
dist=$(realpath "${1:-dist}")
wheel=$(ls -t "$dist"/superfacets-*.whl | head -1)
if [ -n "${2:-}" ]; then mesh=$(realpath "$2")
elif [ -f ../shared/data/meshes/bunny.tri.xz ]; then mesh=$(realpath ../shared/data/meshes/bunny.tri.xz)
else mesh=""; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/env"
"$work/env/bin/python" -m pip install --quiet --upgrade pip
# No compiler reachable: only the environment's own programs on the PATH, and CC/CXX
# pointing nowhere (pip would fail here if it tried to build anything).
nocc() { env PATH="$work/env/bin" CC=/nonexistent CXX=/nonexistent "$@"; }
start=$(date +%s.%N)
nocc "$work/env/bin/python" -m pip install --quiet --only-binary=:all: "$wheel"
took=$(python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" \
  "$start" "$(date +%s.%N)")
sf="$work/env/bin/superfacets"
cd "$work"
nocc "$sf" --version
nocc "$sf" demo --output-dir demo -q   # without the render extra: no picture, said
ls demo
mesh=${mesh:-$work/demo/creature.off}
nocc "$sf" segment "$mesh" -k 50 -o out.seg --colored-mesh out.ply
nocc "$sf" segment "$mesh" --radius 0.05 --init flood -o flood.seg -q
nocc "$sf" baseline "$mesh" -m vsa -k 20 -o vsa.seg -q
nocc "$sf" evaluate "$mesh" out.seg out.seg
nocc "$sf" html "$mesh" out.seg -o out.html -q
test -s out.html
nocc "$sf" batch "$mesh" -o batch-out -k 50 -q   # no Dask, no pyarrow: in process, CSV
test -s batch-out/manifest.csv && head -2 batch-out/manifest.csv
if nocc "$sf" render "$mesh" out.seg -o out.png 2> err.txt; then
  echo "render worked without the render extra?"; exit 1
fi
grep -q "pip install 'superfacets\[render\]'" err.txt && cat err.txt
echo "mesh,method,status" > r.csv
nocc "$sf" report r.csv -o rep 2> err.txt || true
grep -q "pip install 'superfacets\[report\]'" err.txt && cat err.txt
nocc "$work/env/bin/python" -c "import superfacets, sys; print('loaded:', sorted(m for m in ('numba', 'pyvista', 'pandas', 'matplotlib', 'sklearn', 'dask', 'distributed', 'pyarrow') if m in sys.modules))"
if "$work/env/bin/python" -c "import numba" 2>/dev/null; then
  echo "numba was installed with the core?"; exit 1
fi
echo "wheel: $(basename "$wheel") ($(du -h "$wheel" | cut -f1))"
echo "install of the wheel: $took s"
du -sh "$work/env" | sed 's/^/core environment: /'
