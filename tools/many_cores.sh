#!/bin/bash
# Thread and tile scaling on a many-core machine, in one prepared run (never needed by the
# tests or CI): build the package there, then 10M points on 1, 2, 4, 8 and 16 threads (the
# seconds by stage), 4, 8 and 16 tiles on half as many Dask workers as cores, and 100M
# points in one run. Each table is written to OUT as it ends, so a run stopped by its time
# limit keeps what it finished.
#
# Usage, from the repository root of a copy of it:
#   MESH=PSB/off/281.off OUT=/tmp/out [WHEELS=DIR] [LIMIT=585] bash tools/many_cores.sh
#
# MESH: the surface the clouds are sampled on (the benchmark's 281, as tiles_cost.py);
# POINTS, BIG: the clouds' sizes (10M and 100M);
# WHEELS: a folder of wheels for what the machine lacks (trimesh, plyfile, dask,
# distributed and theirs, scikit-build-core, nanobind), installed with no network;
# LIMIT: the seconds the whole run may take (the 100M run gets what is left).
set -u
export PYTHONUNBUFFERED=1
START=$(date +%s)
OUT=${OUT:-/tmp/many-cores}; mkdir -p "$OUT"
MESH=${MESH:?MESH=path of the mesh to sample}
{ nproc; lscpu | head -20; free -g; python3 -V; } > "$OUT/machine.txt" 2>&1
SITE=/tmp/many-cores-site
if [ -n "${WHEELS:-}" ]; then
    python3 -m pip install -q --no-index --no-deps --no-compile --upgrade --target "$SITE/deps" \
        "$WHEELS"/*.whl > "$OUT/build.txt" 2>&1 || { cat "$OUT/build.txt"; exit 1; }
    export PYTHONPATH="$SITE/deps"
fi
python3 -m pip install --no-index --no-deps --no-build-isolation --no-compile \
    --target "$SITE/pkg" . >> "$OUT/build.txt" 2>&1 || { tail -40 "$OUT/build.txt"; exit 1; }
export PYTHONPATH="$SITE/pkg${PYTHONPATH:+:$PYTHONPATH}"
echo "built in $(( $(date +%s) - START )) s"
CORES=$(nproc)
# (the benchmark samples on PSB 281 from SUPERFACETS_PSB: a folder of off/ and seg/)
PSB=$(mktemp -d); mkdir -p "$PSB/off" "$PSB/seg"; cp "$MESH" "$PSB/off/281.off"
export SUPERFACETS_PSB=$PSB SUPERFACETS_CACHE=/tmp/many-cores-cache
POINTS=${POINTS:-10000000}; BIG=${BIG:-100000000}  # (smaller for a dry run)
# the large cloud first, on every core (nothing else runs meanwhile)
python3 tools/sample_cloud.py "$MESH" "$BIG" /tmp/many-cores-big.ply || exit 1
echo "sampled in $(( $(date +%s) - START )) s"
timeout 200 python3 benchmarks/tiles_cost.py --points "$POINTS" -k 2000 \
    --threads 1 2 4 8 16 --tiles > "$OUT/threads.txt" 2> "$OUT/threads.err"
cat "$OUT/threads.txt"
timeout 150 python3 benchmarks/tiles_cost.py --points "$POINTS" -k 2000 --threads 16 \
    --tiles 4 8 16 --workers $(( CORES / 2 > 1 ? CORES / 2 : 1 )) > "$OUT/tiles.txt" 2> "$OUT/tiles.err"
cat "$OUT/tiles.txt"
LEFT=$(( ${LIMIT:-585} - ($(date +%s) - START) ))
echo "$BIG points in one run, $LEFT s left"
[ "$LEFT" -gt 10 ] && timeout "$LEFT" python3 benchmarks/tiles_cost.py \
    --mesh /tmp/many-cores-big.ply -k 20000 --tiles > "$OUT/points100m.txt" 2> "$OUT/points100m.err"
cat "$OUT/points100m.txt" "$OUT/points100m.err"
