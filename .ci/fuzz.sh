#!/usr/bin/env bash
# Fuzzing in CI (issue #38): every cargo-fuzz target of fuzz/ runs for a fixed short
# time, starting from its committed corpus (fuzz/corpus/<target>/), two at a time on the
# two cores. A run fails on a panic (or a broken guarantee the harness asserts), an
# input taking over 10 s, a live Rust heap over the fuzz binaries' cap
# (fuzz/src/heap_cap.rs: 256 MiB) or a process over 1 GiB resident. First the negative
# controls: the `selftest` binary must fail on a panic and on an allocation over the cap.
#
# Needs only the stable toolchain (cargo-fuzz with `-s none`, see docs/fuzzing.md) and
# crates.io. Called from .ci/run; runnable on its own: bash .ci/fuzz.sh
# (FATHOM_FUZZ_SECONDS sets the time per target, default 30).
set -euo pipefail
cd "$(dirname "$0")/.."

SECONDS_PER_TARGET="${FATHOM_FUZZ_SECONDS:-30}"
CARGO_FUZZ_VERSION=0.13.2
RSS_LIMIT_MB=1024
TIMEOUT_S=10

if ! cargo fuzz --version 2>/dev/null | grep -qF "${CARGO_FUZZ_VERSION}"; then
  echo "== fuzz: installing cargo-fuzz ${CARGO_FUZZ_VERSION}"
  cargo install --locked --quiet cargo-fuzz --version "${CARGO_FUZZ_VERSION}"
fi

echo "== fuzz: building every target (instrumented, release with debug assertions)"
cargo fuzz build -s none
host="$(rustc -vV | sed -n 's/^host: //p')"
bin_dir="fuzz/target/${host}/release"
work="$(mktemp -d /tmp/fathom-fuzz.XXXXXX)"

echo "== fuzz: negative controls (the selftest binary must fail)"
printf panic >"${work}/panic"
printf alloc >"${work}/alloc"
control() {
  local input="$1" expect="$2"
  if "${bin_dir}/selftest" -rss_limit_mb="${RSS_LIMIT_MB}" "${work}/${input}" \
    >"${work}/control_${input}.log" 2>&1; then
    echo "negative control '${input}': the selftest binary did not fail" >&2
    exit 1
  fi
  if ! grep -qF "${expect}" "${work}/control_${input}.log"; then
    echo "negative control '${input}': failed without '${expect}':" >&2
    tail -20 "${work}/control_${input}.log" >&2
    exit 1
  fi
  echo "   ${input}: fails as it must ($(grep -m1 -F "${expect}" "${work}/control_${input}.log"))"
}
control panic "selftest: a panic must fail the fuzz run"
control alloc "memory allocation of"

# One target: libFuzzer with the committed corpus as the second corpus folder (read),
# new inputs into a scratch folder (first), crash inputs into fuzz/artifacts/<target>/.
fuzz_one() {
  local t="$1"
  mkdir -p "${work}/new_${t}" "fuzz/artifacts/${t}"
  if "${bin_dir}/${t}" -max_total_time="${SECONDS_PER_TARGET}" -timeout="${TIMEOUT_S}" \
    -rss_limit_mb="${RSS_LIMIT_MB}" -print_final_stats=1 \
    -artifact_prefix="fuzz/artifacts/${t}/" "${work}/new_${t}" "fuzz/corpus/${t}" \
    >"${work}/${t}.log" 2>&1; then
    echo ok >"${work}/${t}.status"
  else
    echo "failed (exit $?)" >"${work}/${t}.status"
  fi
}

targets=()
for f in fuzz/fuzz_targets/*.rs; do
  t="$(basename "$f" .rs)"
  [ "$t" = selftest ] || targets+=("$t")
done
echo "== fuzz: ${#targets[@]} targets, ${SECONDS_PER_TARGET} s each, two at a time"
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge 2 ]; do wait -n || true; done
  fuzz_one "$t" &
done
wait

failed=0
printf '   %-14s %-8s %10s %8s %6s  %s\n' target corpus executions edges new result
for t in "${targets[@]}"; do
  log="${work}/${t}.log"
  status="$(cat "${work}/${t}.status")"
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  edges="$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)"
  corpus="$(find "fuzz/corpus/${t}" -type f | wc -l)"
  new="$(find "${work}/new_${t}" -type f | wc -l)"
  printf '   %-14s %-8s %10s %8s %6s  %s\n' "$t" "$corpus" "${execs:-?}" "${edges:-?}" "$new" "$status"
  if [ "$status" != ok ]; then
    failed=1
    echo "---- ${t}: the end of libFuzzer's output" >&2
    tail -40 "$log" >&2
    ls -l "fuzz/artifacts/${t}/" >&2
  fi
done
[ "$failed" = 0 ] || { echo "fuzz: a target failed; the input is in fuzz/artifacts/<target>/ (see docs/fuzzing.md)" >&2; exit 1; }
echo "fuzz done"
