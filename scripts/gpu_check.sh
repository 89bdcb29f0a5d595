#!/usr/bin/env bash
# The device check of mgpbd's GPU solve phase (docs/gpu.md), in two steps:
#
#   scripts/gpu_check.sh prepare [BUILD]   on the CPU machine, with the build (default: build/):
#       captures squash bunny:270k (frame 0, outer iteration 3) and cloth_hang 512² (frame 1, outer iteration 0:
#       its frame 0 converges at once),
#       and the smaller squash bunny:50k and cloth_hang 256², into gpu_captures/ (ignored by git);
#       writes mgpbd's hierarchy into each (xpbd_bench.export_hierarchy: the primal form of the
#       squash, the dual of the cloth); solves each with C++ mgpbd on this machine's cores to the
#       dual 1e-8 and 0.1 (gpu_captures/cpu_mgpbd.json: the column to compare against); and packs
#       the .h5 files into parts gpu_captures/parts/NN/chunk, each small enough to travel with
#       the working tree in one device call (64 MiB in all: python/xpbd_bench/device_parts.py
#       measures the tree now and sizes the parts to fit beside it).
#   scripts/gpu_check.sh run                on the device machine, Python only (no C++ build):
#       joins the parts, makes sure CuPy imports (pip-installs cupy-cuda12x if absent, or the
#       wheels carried in .whl/), runs python3 -m xpbd_bench.gpu_bench --backend cupy on every
#       capture to 1e-8 and the race's loose 0.1, and writes one JSON: $OUT/gpu_check.json
#       (gpu_captures/ without $OUT). Without CuPy or a device it fails: it never measures NumPy
#       in the device's place.
#
# SIZES=small limits both steps to the two smaller captures (one part: a single device call).
# BENCH_ARGS adds gpu_bench options after --backend cupy (a dry run here, on the CPU:
# BENCH_ARGS="--backend numpy --no-baseline --tol 0.1").
# Every part is carried by one device call on the same warm machine (ignored files stay there
# between calls): carry gpu_captures/parts/00, then 01, ..., the last call running
# `bash scripts/gpu_check.sh run` (docs/gpu.md gives the calls).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
dir=gpu_captures
step="${1:-run}"

captures() {  # name scene frame iteration form set...
  if [ "${SIZES:-all}" = small ]; then
    echo "squash50k squash 0 3 primal mesh=bunny:50k"
    echo "cloth256 cloth_hang 1 0 dual resolution=256"
  else
    echo "squash50k squash 0 3 primal mesh=bunny:50k"
    echo "cloth256 cloth_hang 1 0 dual resolution=256"
    echo "squash270k squash 0 3 primal mesh=bunny:270k"
    echo "cloth512 cloth_hang 1 0 dual resolution=512"
  fi
}

prepare() {
  local build="${1:-build}"
  local bench="$build/xpbd-bench"
  [ -x "$bench" ] || { echo "gpu_check prepare: $bench not found (build the project first)" >&2; exit 1; }
  mkdir -p "$dir"
  export XB_MESH_DIR="${XB_MESH_DIR:-$root/data/meshes}" PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}"
  rm -f "$dir/cpu_mgpbd.h5"
  while read -r name scene frame iteration form sets; do
    local args=()
    for s in $sets; do args+=(--set "$s"); done
    if [ ! -f "$dir/$name.h5" ]; then
      echo "capture $name ..." >&2
      case "$sets" in *bunny:*) scripts/get_meshes.sh "${sets#mesh=}" >&2 ;; esac
      "$bench" capture --scene "$scene" --frame "$frame" --iteration "$iteration" "${args[@]}" --out "$dir/$name" --quiet
      rm -f "$dir/${name}"_*.mtx  # Matrix Market copies: not needed on the device
    fi
    python3 -c "import sys, xpbd_bench as xb; print(xb.export_hierarchy(sys.argv[1], forms=sys.argv[2]))" "$dir/$name.h5" "$form"
    for tol in 1e-8 0.1; do  # the C++ column of the table, on this machine's cores
      "$bench" solve --system "$dir/$name.h5" --solver mgpbd --form "$form" --tol "$tol" --out "$dir/cpu_$name.h5" --quiet
      "$bench" report "$dir/cpu_$name.h5" --format json > "$dir/cpu_${name}_$tol.json"
      rm -f "$dir/cpu_$name.h5"
    done
  done < <(captures)
  python3 - "$dir" <<'EOF'
import glob, json, os, sys
d = sys.argv[1]
rows = []
for f in sorted(glob.glob(os.path.join(d, "cpu_*_*.json"))):
    for r in json.load(open(f)):
        rows.append({k: r.get(k) for k in ("system", "form_used", "rows", "iterations", "solve_time", "setup_time",
                                           "final_relative_residual", "status")} | {"tol": float(f.rsplit("_", 1)[1][:-5])})
json.dump({"machine": os.uname().nodename, "cores": os.cpu_count(), "load": os.getloadavg(), "runs": rows},
          open(os.path.join(d, "cpu_mgpbd.json"), "w"), indent=1)
EOF
  rm -rf "$dir/parts" "$dir/carry"
  mkdir -p "$dir/parts" "$dir/carry"
  local list=()
  while read -r name _; do  # what gpu_bench reads, compressed (hierarchy_io.slim_copy)
    python3 -c "import sys; from xpbd_bench import hierarchy_io as h; h.slim_copy(sys.argv[1], sys.argv[2])" \
      "$dir/$name.h5" "$dir/carry/$name.h5"
    list+=("$name.h5")
  done < <(captures)
  cp "$dir/cpu_mgpbd.json" "$dir/carry/"
  tar -C "$dir/carry" -cf "$dir/captures.tar" "${list[@]}" cpu_mgpbd.json
  PYTHONPATH="$root/python" python3 -m xpbd_bench.device_parts split "$dir/captures.tar" "$dir/parts" --root "$root"
  rm -f "$dir/captures.tar"
  ls -l "$dir"/parts/*/chunk >&2
  echo "gpu_check prepare: $(ls -d "$dir"/parts/*/ | wc -l) part(s); carry each in turn (docs/gpu.md)" >&2
}

run() {
  mkdir -p "$dir/carry"
  cat "$dir"/parts/*/chunk | tar -C "$dir/carry" -xf -
  if command -v nvidia-smi >/dev/null && ! python3 -c "import cupy" 2>/dev/null; then
    if ls .whl/*.whl >/dev/null 2>&1; then
      python3 -m pip install -q --no-index --no-deps --target /tmp/site .whl/*.whl && export PYTHONPATH=/tmp/site
    else
      python3 -m pip install -q cupy-cuda12x || echo "gpu_check: CuPy is missing and could not be installed" >&2
    fi
  fi
  command -v nvidia-smi >/dev/null || echo "gpu_check: no nvidia-smi: no device here (gpu_bench --backend cupy will fail)" >&2
  nvidia-smi --query-gpu=name,memory.total,clocks.max.memory --format=csv,noheader || true
  local out="${OUT:-$dir}/gpu_check.json"
  local list=()
  while read -r name _; do [ -f "$dir/carry/$name.h5" ] && list+=("$dir/carry/$name.h5"); done < <(captures)
  PYTHONPATH="$root/python${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1 \
    python3 -m xpbd_bench.gpu_bench "${list[@]}" --out "$out" --tol 1e-8 0.1 --repeat 3 --backend cupy ${BENCH_ARGS:-}
  cp "$dir/carry/cpu_mgpbd.json" "${OUT:-$dir}/cpu_mgpbd.json" 2>/dev/null || true
  echo "gpu_check: wrote $out" >&2
}

case "$step" in
  prepare) shift; prepare "$@" ;;
  run) run ;;
  *) echo "usage: scripts/gpu_check.sh prepare [BUILD] | run" >&2; exit 2 ;;
esac
