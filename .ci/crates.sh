#!/usr/bin/env bash
# Each library crate on its own (issue #39, "pick-and-choose crates"): a user adds
# one of them to a project without the rest of the workspace, so CI checks that
#
#   1. each library crate builds and passes its tests alone (`cargo test -p <crate>`:
#      only that crate's features, its examples built, its README doc-tested; for
#      fathom-estimators `check --all-targets` and its doc tests, its unit tests having
#      run in the workspace with the same features), and its examples run;
#   2. `cargo package --list` of each crate ships its README and licence files, and
#      `cargo package --no-verify` of all of them succeeds;
#   3. the library crates' API docs build with warnings as errors;
#   4. a scratch project outside the workspace that depends on `fathom-estimators`
#      alone (by path) builds and runs that crate's README example; its dependency
#      tree has no other fathom library, and none of serde or rand without the
#      default features.
#
# Cheap by construction: the same target directory and the `test` profile as the main
# `cargo test --workspace`, so most dependencies are already built; the scratch project
# gets the workspace's Cargo.lock and profile settings so that it reuses them too.
# Called from .ci/run after the Rust tests; runnable on its own: bash .ci/crates.sh
set -euo pipefail
cd "$(dirname "$0")/.."

ROOT="$(pwd)"
TARGET_DIR="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
export CARGO_TARGET_DIR="${TARGET_DIR}"

LIBS=(fathom-core fathom-traj fathom-sensors fathom-stats fathom-estimators fathom-ins fathom-map fathom-report fathom-data)

# Prints how long a step took (seconds), so that CI logs show what this script costs.
timed() {
  local start=$SECONDS
  "$@"
  echo "   [$((SECONDS - start)) s] $*"
}

echo "== crates: each library crate tested alone"
for c in "${LIBS[@]}"; do
  if [ "$c" = fathom-estimators ]; then
    # Its unit tests already ran in `cargo test --workspace` with the same (default)
    # features; alone, its test build costs ~3.5 min, so here it is compiled alone
    # (all targets) and its README and doc examples run.
    timed cargo check -q -p "$c" --all-targets
    timed cargo test -q -p "$c" --doc
  else
    timed cargo test -q -p "$c"
  fi
done

echo "== crates: the crates' examples run (test profile, as built above)"
for ex in crates/*/examples/*.rs; do
  c="$(basename "$(dirname "$(dirname "$ex")")")"
  name="$(basename "$ex" .rs)"
  start=$SECONDS
  cargo run -q --profile test -p "$c" --example "$name" >/dev/null
  echo "   [$((SECONDS - start)) s] $c: example $name"
done

echo "== crates: cargo package --list ships README and licences"
for c in "${LIBS[@]}"; do
  list="$(cargo package --list --allow-dirty -p "$c")"
  for f in Cargo.toml README.md LICENSE-MIT LICENSE-APACHE src/lib.rs; do
    if ! grep -qx "$f" <<<"$list"; then
      echo "cargo package -p $c does not ship $f" >&2
      exit 1
    fi
  done
  echo "   $c: $(wc -l <<<"$list") files"
done

echo "== crates: cargo package of every library crate (path dependencies as registry versions)"
# One call for all of them: cargo packages the crates in dependency order and resolves
# each one's fathom dependencies against the others just packaged (its local overlay
# registry), so this needs no publishing and holds although crates.io has unrelated
# crates of some of these names (see README "Using one crate").
pkg_args=()
for c in "${LIBS[@]}"; do pkg_args+=(-p "$c"); done
timed cargo package -q --no-verify --allow-dirty "${pkg_args[@]}"

echo "== crates: API docs of the library crates with warnings as errors"
doc_args=()
for c in "${LIBS[@]}"; do doc_args+=(-p "$c"); done
RUSTDOCFLAGS="-D warnings" timed cargo doc -q --no-deps "${doc_args[@]}"

echo "== crates: a scratch project depending on fathom-estimators alone runs its README example"
scratch="$(mktemp -d /tmp/fathom-scratch.XXXXXX)"
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$scratch/src"
nalgebra_version="$(sed -n 's/^nalgebra = .*"\([0-9.]*\)".*/\1/p' Cargo.toml | head -1)"
cat >"$scratch/Cargo.toml" <<TOML
[package]
name = "scratch-user"
version = "0.1.0"
edition = "2024"
publish = false

[dependencies]
fathom-estimators = { path = "${ROOT}/crates/fathom-estimators" }
fathom-core = { path = "${ROOT}/crates/fathom-core" }
nalgebra = "${nalgebra_version}"

# the workspace's settings, so that what the tests above built is reused: its
# dependencies at opt-level 2, fathom-estimators at the test profile's opt-level 3,
# fathom-core (a path dependency, so also matched by "*") at the profile's 1
[profile.dev.package."*"]
opt-level = 2

[profile.test]
opt-level = 1

[profile.test.package.fathom-estimators]
opt-level = 3

[profile.test.package.fathom-core]
opt-level = 1
TOML
cp Cargo.lock "$scratch/Cargo.lock"
# The README's first Rust block is the whole program (it has its own `fn main`).
awk '/^```rust$/ {inside = 1; next} inside && /^```$/ {exit} inside {print}' \
  crates/fathom-estimators/README.md >"$scratch/src/main.rs"
grep -q '^fn main' "$scratch/src/main.rs"
(cd "$scratch" && timed cargo run -q --profile test)
if (cd "$scratch" && cargo tree -e normal --prefix none | grep -E '^fathom-(sensors|traj|map|sim|ins|stats) '); then
  echo "the scratch project pulls in a fathom crate that fathom-estimators must not need" >&2
  exit 1
fi
# Without its default features the Kalman core needs no serde and no rand (checked on
# the dependency tree only: building that variant rebuilds faer without serde, ~3 min).
minimal_tree="$(cargo tree -e normal --prefix none -p fathom-estimators --no-default-features)"
if grep -E '^(serde|rand|rand_distr) ' <<<"$minimal_tree"; then
  echo "fathom-estimators without default features still depends on serde or rand" >&2
  exit 1
fi
core_tree="$(cargo tree -e normal --prefix none -p fathom-core)"
if grep -E '^serde ' <<<"$core_tree"; then
  echo "fathom-core depends on serde without its serde feature" >&2
  exit 1
fi
echo "   the README example of fathom-estimators ran in a project of its own"
