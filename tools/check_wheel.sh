#!/usr/bin/env bash
# Build a wheel, install it with no extras in a fresh virtual environment, and check that
# the core commands work there and that the others name the extra to install.
# Usage: tools/check_wheel.sh [MESH]   (prints the environment's size at the end)
# MESH: default the bunny of ../shared beside the repository, else the demo's mesh.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "${1:-}" ]; then mesh=$(realpath "$1")
elif [ -f ../shared/data/meshes/bunny.tri.xz ]; then mesh=$(realpath ../shared/data/meshes/bunny.tri.xz)
else mesh=""; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/env"
"$work/env/bin/python" -m pip install --quiet --upgrade pip
"$work/env/bin/python" -m pip wheel --quiet --no-deps -w "$work/dist" .
"$work/env/bin/python" -m pip install --quiet "$work"/dist/superfacets-*.whl
sf="$work/env/bin/superfacets"
cd "$work"
"$sf" --version
"$sf" demo --output-dir demo -q   # without the render extra: no picture, said
ls demo
mesh=${mesh:-$work/demo/creature.off}
"$sf" segment "$mesh" -k 50 -o out.seg --colored-mesh out.ply
"$sf" evaluate "$mesh" out.seg out.seg
"$sf" html "$mesh" out.seg -o out.html -q
test -s out.html
"$sf" batch "$mesh" -o batch-out -k 50 -q   # no Dask, no pyarrow: in process, CSV
test -s batch-out/manifest.csv && head -2 batch-out/manifest.csv
if "$sf" render "$mesh" out.seg -o out.png 2> err.txt; then
  echo "render worked without the render extra?"; exit 1
fi
grep -q "pip install 'superfacets\[render\]'" err.txt && cat err.txt
echo "mesh,method,status" > r.csv
"$sf" report r.csv -o rep 2> err.txt || true
grep -q "pip install 'superfacets\[report\]'" err.txt && cat err.txt
"$work/env/bin/python" -c "import superfacets, sys; print(sorted(m for m in ('pyvista', 'pandas', 'matplotlib', 'sklearn', 'skimage', 'dask', 'distributed', 'pyarrow') if m in sys.modules))"
du -sh "$work/env" | sed 's/^/core environment: /'
