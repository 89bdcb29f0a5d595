#!/usr/bin/env bash
# The measurements behind docs/newton.md's "The collapsed squash at 270K: a certified truth": the
# trust region against the line search on the collapsed squash, the exact Hessian's inertia at the
# end, and Newton started from XPBD's end state. Each section prints what the doc's tables hold;
# run on a quiet machine (timings), from the repository root after building (build/).
#
#   scripts/trust_region_squash.sh small       # bunny:12k, 50k: iterations of every globalisation
#   scripts/trust_region_squash.sh certify M   # M = bunny:270k | elephant:270k | bunny:50k ...: the trust
#                                              # region to 1e-10, then CHOLMOD on the exact K and λ_min
#   scripts/trust_region_squash.sh reference   # the 30-minute criterion: --reference with the trust region
#   scripts/trust_region_squash.sh xpbd M      # Newton from XPBD's end state against Newton from x̃
#
# Meshes: scripts/get_meshes.sh NAME:SIZE (XB_MESH_DIR shares them). Output under ${OUT:-/tmp/trn}.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bench=build/xpbd-bench
measure=build/tests/xb_newton_measure
out=${OUT:-/tmp/trn}
mkdir -p "$out"
echo "1-min load at start: $(cut -d' ' -f1 /proc/loadavg)"

summary() {  # FILE [reference]: status, iterations, final relative |grad E| of each run (or of its reference)
  python3 - "$@" <<'EOF'
import sys, h5py
def runs(g):
    for k in g:
        if isinstance(g[k], h5py.Group):
            if 'iteration' in g[k]: yield g[k]
            else: yield from runs(g[k])
def text(v):
    return v.decode() if isinstance(v, bytes) else v
with h5py.File(sys.argv[1]) as h:
    for g in runs(h):
        if sys.argv[2:] == ["reference"]:
            print("reference:", text(g['reference/status'][0]), int(g['reference/iterations'][0]),
                  f"iterations, relative |grad E| {g['reference/relative_energy_gradient'][0]:.2e}, "
                  f"{g.attrs['reference_time']:.1f} s")
        else:
            print(f"  {text(g.attrs['status'])}, {int(g.attrs['outer_iterations'])} iterations, final relative |grad E| "
                  f"{g['relative_newton_residual'][-1]:.2e}, wall {g.attrs['wall_time']:.1f} s")
EOF
}

case "${1:-}" in
  small)
    for mesh in bunny:12k bunny:50k; do
      for v in "line_search - cholmod" "trust_region steihaug cholmod" "trust_region steihaug mgpbd" \
               "trust_region more_sorensen cholmod"; do
        set -- $v
        keys=(--set "mesh=$mesh")
        [ "$1" = trust_region ] && keys+=(--set xpbd.globalization=trust_region --set "xpbd.trust_region_subproblem=$2")
        f="$out/small_${mesh/:/_}_$1_$2_$3.h5"
        "$bench" run --scene squash --solver "$3" --profile newton --frames 1 "${keys[@]}" --out "$f" > /dev/null
        echo "$mesh $1 $2 $3:"; summary "$f"
      done
    done ;;
  certify)
    mesh=${2:?mesh}
    /usr/bin/time -f "%U s user, %e s wall" "$measure" --scene squash --set "mesh=$mesh" \
      --set xpbd.globalization=trust_region --set max_iterations=150 --set rtol=1e-10 --set atol=0 \
      --save-end "$out/certify_${mesh/:/_}.h5" --bracket ;;
  reference)
    /usr/bin/time -f "%U s user, %e s wall" "$bench" run --scene squash --set mesh=bunny:270k --frames 1 \
      --profile newton --solver cholmod --set max_iterations=1 --reference \
      --set reference.globalization=trust_region --out "$out/reference_270k.h5" > /dev/null || true
    summary "$out/reference_270k.h5" reference
    ;;
  xpbd)
    mesh=${2:?mesh}
    tag=${mesh/:/_}
    "$bench" run --scene squash --solver cholmod --set "mesh=$mesh" --frames 1 \
      --save-state "$out/xpbd_$tag.h5" --frame-of-state 0 --out "$out/xpbd_run_$tag.h5" > /dev/null || true
    echo "XPBD (cholmod, defaults):"; summary "$out/xpbd_run_$tag.h5"
    "$measure" --scene squash --set "mesh=$mesh" --set rtol=1e-10 --set atol=0 --save-end "$out/newton_$tag.h5" \
      | grep -E '^(end|squash)'
    for g in line_search trust_region; do
      echo "Newton ($g) from XPBD's end:"
      "$measure" --scene squash --set "mesh=$mesh" --set rtol=1e-10 --set atol=0 --set "xpbd.globalization=$g" \
        --start "$out/xpbd_$tag.h5" --compare "$out/newton_$tag.h5" | grep -E '^(0 |end|compare)'
    done ;;
  *) sed -n 2,13p "$0"; exit 2 ;;
esac
