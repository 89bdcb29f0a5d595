#!/usr/bin/env bash
# Runs fuzz targets one after the other: bash fuzz/run.sh BUILD SECONDS TARGET...
# Each target starts from its seeds (the test data, rebuilt here each time) and its corpus of
# earlier runs (BUILD/corpus/TARGET, kept). A finding stops the script with the input under
# BUILD/findings/TARGET/; the last line per target gives its executions and executions per second.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$1 seconds=$2
shift 2

# TetGen inputs hold both files: the .node text, a line "@@ele", the .ele text.
tetgen_seeds() {
  local node
  for node in tests/data/good/*.node tests/data/broken/*.node; do
    { cat "$node"; printf '\n@@ele\n'; [[ -f ${node%.node}.ele ]] && cat "${node%.node}.ele"; } >"$1/$(basename "$node")"
  done
}

seed() {
  local dir=$build/seeds/$1
  rm -rf "$dir" && mkdir -p "$dir"
  case $1 in
    tetgen) tetgen_seeds "$dir" ;;
    gmsh) cp tests/data/good/*.msh tests/data/broken/*.msh "$dir" ;;
    medit) cp tests/data/good/*.mesh tests/data/broken/*.mesh "$dir" ;;
    scene) cp problems/scenes/*.toml "$dir" ;;
    sweep) cp figures/*.toml "$dir" ;;
    system | results) cp fuzz/seeds/"$1"/* "$dir" ;;
    *) echo "fuzz: unknown target '$1'" >&2; exit 2 ;;
  esac
  # Earlier findings of this reader replay first: each must now end in a clear error.
  if [[ -d tests/data/fuzz_findings/$1 ]]; then cp tests/data/fuzz_findings/"$1"/* "$dir"; fi
}

# Text inputs stay small; the HDF5 seeds are 16-52 KB.
max_len() { case $1 in system | results) echo 65536 ;; *) echo 4096 ;; esac; }

for t in "$@"; do
  seed "$t"
  mkdir -p "$build/corpus/$t" "$build/findings/$t"
  echo "fuzz: $t for $seconds s"
  "$build/fuzz/${t}_fuzz" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -max_len="$(max_len "$t")" \
    -print_final_stats=1 -artifact_prefix="$build/findings/$t/" "$build/corpus/$t" "$build/seeds/$t" \
    >"$build/$t.log" 2>&1 || { tail -60 "$build/$t.log"; echo "fuzz: $t: FINDING (input under $build/findings/$t/)"; exit 1; }
  awk -v t="$t" '/stat::number_of_executed_units/ {n=$2} /stat::average_exec_per_sec/ {r=$2}
    END {printf "fuzz: %s: %d executions, %d/s, no finding\n", t, n, r}' "$build/$t.log"
done
