#!/usr/bin/env bash
# The second half of issue #38's generated test: every variant the e2e test
# `every_key` accepts (a numeric key of a preset set to 0, -1, NaN, inf, 1e-300 or
# 1e300 that `check` lets through) is run with the release `fathom` (2 Monte Carlo
# runs where the experiment has runs) and must exit 0 with no null, NaN or infinite
# value in its summary.json. Not part of .ci/run (about 5 min on 2 cores); run it
# after changing checks: bash .ci/every-key-runs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"
target="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
work="$target/every-key-runs"
rm -rf "$work"
mkdir -p "$work/scenarios"
# the variants name worlds beside them and data folders from the current directory
cp -r scenarios/worlds "$work/scenarios/"
ln -s "$root/data" "$work/data"

FATHOM_EVERY_KEY_DUMP="$work/scenarios" \
  cargo test -q --workspace -- every_key::every_numeric_key_set >/dev/null
cargo build --release -q -p fathom-cli --bin fathom
fathom="$target/release/fathom"

total=0
failed=0
start=$SECONDS
for f in "$work"/scenarios/0*.toml; do
  total=$((total + 1))
  what="$(head -1 "$f" | sed 's/^# //')"
  name="$(basename "$f" .toml)"
  args=(run "$f" --out "$work/out/$name" --force --threads 1)
  case "$what" in
    scenarios/beacons.toml:* | scenarios/fusion.toml:* | scenarios/noise.toml:* | \
      scenarios/vkf.toml:* | scenarios/urban.toml:*) args+=(--runs 2) ;;
  esac
  if ! (cd "$work" && timeout 300 "$fathom" "${args[@]}" >"$work/$name.log" 2>&1); then
    echo "FAILED: $what: $(tail -1 "$work/$name.log")"
    failed=$((failed + 1))
  elif grep -qE '"value": null|NaN|Infinity' "$work/out/$name/summary.json"; then
    echo "NOT FINITE: $what: $work/out/$name/summary.json"
    failed=$((failed + 1))
  fi
done
echo "$total accepted variants run in $((SECONDS - start)) s: $failed failed or not finite"
[ "$failed" = 0 ]
