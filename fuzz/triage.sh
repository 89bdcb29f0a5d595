#!/usr/bin/env bash
# Which side a finding is on (fuzz/README.md): bash fuzz/triage.sh BUILD TARGET [INPUT...]
# (no INPUT: every crash, leak, oom and timeout in BUILD/findings/TARGET/). Per input: the report's kind, the first frame
# outside the sanitizer runtime, libFuzzer, libc and malloc, and the verdict: "libhdf5" when that frame is in libhdf5 and
# no frame of the memory's allocation is ours, "no report" when the input reruns cleanly (exit 0, no report: in fork
# mode libFuzzer saves such inputs, often empty, when a child dies without a report of its own, e.g. killed for
# time or memory as a whole), else "ours"; last, our innermost frame. A timeout is "ours" until read: its stack is a
# snapshot (a loop of ours over a count it never checked is ours).
set -uo pipefail
build=$1 target=$2
shift 2
(($#)) || set -- "$build/findings/$target"/{crash,leak,oom,timeout}-*
for input in "$@"; do
  [[ -f $input ]] || continue
  report=$("$build/fuzz/${target}_fuzz" -timeout=20 -rss_limit_mb=2048 "$input" 2>&1)
  status=$?
  kind=$(grep -m1 -oE '(AddressSanitizer|UndefinedBehaviorSanitizer|LeakSanitizer): [A-Za-z-]+|libFuzzer: [a-z-]+|runtime error: .*|fuzz: not an xb::Error.*|deadly signal' <<<"$report")
  # The crash stack is the report's first stack; frames of the sanitizer runtime are skipped.
  first=$(awk '/^    #[0-9]+ /{ if ($0 ~ /__interceptor_|__asan|__sanitizer|fuzzer::| in (malloc|calloc|realloc|free) |libc\.so|sysdeps\//) next; print; exit }' <<<"$report")
  alloc=$(awk '/allocated by thread/{a=1; next} a && /^$/{exit} a' <<<"$report")
  if [[ -z $kind && $status == 0 ]]; then verdict="no report"
  elif [[ $first == *libhdf5* && $kind != *timeout* ]] && ! grep -q ' in xb::' <<<"$alloc"; then verdict=libhdf5
  else verdict=ours; fi
  frame=$(sed -E 's/^ +#[0-9]+ 0x[0-9a-f]+ (in )?//; s/ \(BuildId.*//' <<<"$first")
  ours=$(grep -m1 -oE ' in xb::[^(]*\(| /[^ ]*/(harness|problems|solvers)/[^ ]*' <<<"$report" | tr '\n' ' ')
  printf '%s\t%s\t%s\t%s\t%s\n' "$(basename "$input")" "$verdict" "${kind:-none (reran: exit $status, $(wc -c <"$input") bytes)}" "$frame" "$ours"
done
