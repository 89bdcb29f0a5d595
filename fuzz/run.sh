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
    # Edit lists (fuzz/h5_edits.hpp): each seed file as it is, and one edit of it.
    system_struct | results_struct) printf '\0' >"$dir/seed0"; printf '\1' >"$dir/seed1"; printf '\0\0\0\0' >"$dir/edit" ;;
    *) echo "fuzz: unknown target '$1'" >&2; exit 2 ;;
  esac
  # Earlier findings in this reader replay first: each must now end in a clear error. Those in
  # libhdf5 itself (fuzz_findings/TARGET/libhdf5/) are kept as a record only.
  if [[ -d tests/data/fuzz_findings/$1 ]]; then find tests/data/fuzz_findings/"$1" -maxdepth 1 -type f -exec cp {} "$dir" \;; fi
}

# A spec's solver list starts Open MPI (parse_methods asks for the number of ranks), which keeps
# what MPI_Init allocated past MPI_Finalize: LeakSanitizer would report it at exit (libFuzzer's
# -detect_leaks covers its per-input check only, ASAN_OPTIONS the one at exit).
leaks() { case $1 in sweep) echo 0 ;; *) echo 1 ;; esac; }

# An edit list (fuzz/h5_edits.hpp) is short, and one of a few bytes makes one or two edits: the
# *_struct targets take inputs of any length up to 256 bytes from the start (libFuzzer's length
# control would keep them to a few bytes for most of a run at ~10-60 executions a second).
len_flags() { case $1 in *_struct) echo "-max_len=256 -len_control=0" ;; *) echo "-max_len=4096" ;; esac; }

# libhdf5 1.10 itself crashes on many corrupt files (fuzz/README.md): the HDF5 targets run in fork
# mode past crashes, and only a finding that triage.sh puts on our side fails.
hdf5_run() {
  local t=$1
  # libFuzzer's timeout handler can deadlock a child in the allocator (seen once here), which
  # hangs fork mode: the whole process group is killed 120 s after its time, and what it saved
  # is triaged as usual.
  ASAN_OPTIONS=detect_leaks=1 timeout -s KILL $((seconds + 120)) "$build/fuzz/${t}_fuzz" -fork=1 -ignore_crashes=1 \
    -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$build/findings/$t/" "$build/corpus/$t" "$build/seeds/$t" >"$build/$t.log" 2>&1 ||
    echo "fuzz: $t: stopped after $((seconds + 120)) s (libFuzzer hung)"
  compgen -G "$build/findings/$t/[clot]*-*" >/dev/null || return 0
  bash fuzz/triage.sh "$build" "$t" >"$build/$t.triage"
  echo "fuzz: $t: $(grep -c $'\tlibhdf5\t' "$build/$t.triage") finding(s) inside libhdf5, $(grep -c $'\tno report\t' "$build/$t.triage")" \
    "saved without a report that rerun cleanly (list: $build/$t.triage)"
  ! grep -q $'\tours\t' "$build/$t.triage"
}

for t in "$@"; do
  seed "$t"
  mkdir -p "$build/corpus/$t" "$build/findings/$t"
  echo "fuzz: $t for $seconds s"
  case $t in
    system | results) hdf5_run "$t" || { grep $'\tours\t' "$build/$t.triage"; echo "fuzz: $t: FINDING in our reader"; exit 1; } ;;
    *) ASAN_OPTIONS=detect_leaks=$(leaks "$t") "$build/fuzz/${t}_fuzz" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 \
         $(len_flags "$t") -detect_leaks="$(leaks "$t")" -print_final_stats=1 -artifact_prefix="$build/findings/$t/" \
         "$build/corpus/$t" "$build/seeds/$t" >"$build/$t.log" 2>&1 ||
         { tail -60 "$build/$t.log"; echo "fuzz: $t: FINDING (input under $build/findings/$t/)"; exit 1; } ;;
  esac
  awk -v t="$t" '/stat::number_of_executed_units/ {n=$2} /stat::average_exec_per_sec/ {r=$2}
    END {printf "fuzz: %s: %d executions, %d/s\n", t, n, r}' "$build/$t.log"
done
