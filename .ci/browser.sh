#!/usr/bin/env bash
# CI step: the 3D scene page (scene.html, issue 40) in a real headless Chromium. A
# short `urban` run (2 Monte Carlo runs of the preset: bridge and buildings) writes
# the page; .ci/scene-page.cjs (playwright-core from the npm registry) opens it from
# disk, checks the first frame, the console, the canvas, the slider and the bridge's
# mode switches, and saves screenshots under target/browser-test/.
#
# Needs Chromium (Debian package `chromium`) and node/npm: as root with apt-get the
# step installs what is missing; otherwise it says so and exits 0 without running
# (never silently). FATHOM_SCENE_DOCS=1 also copies the screenshots to docs/img/ (the
# README's pictures).
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
target="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
work="$target/browser-test"
CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"

need=()
[ -x "$CHROMIUM" ] || need+=(chromium)
command -v node >/dev/null && command -v npm >/dev/null || need+=(nodejs npm)
if [ "${#need[@]}" -gt 0 ]; then
  if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null; then
    echo "SKIPPED: the browser step needs ${need[*]} (root and apt-get to install them; uid $(id -u))"
    exit 0
  fi
  echo "installing ${need[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get update -q >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${need[@]}" >/dev/null
fi

# playwright-core (no bundled browsers: it drives the Debian Chromium), into target/
mkdir -p "$work"
if [ ! -d "$work/node_modules/playwright-core" ]; then
  (cd "$work" && npm install --no-audit --no-fund --no-save playwright-core@1 >/dev/null)
fi

# the release binary (already built by the earlier steps of .ci/run)
cargo build --release -q -p fathom-cli --bin fathom
FATHOM="$target/release/fathom"

out="$work/urban"
"$FATHOM" run scenarios/urban.toml --runs 2 --threads 2 --out "$out" --force >/dev/null
page=$("$FATHOM" view "$out" --no-open)
echo "page: $page ($(du -k "$page" | cut -f1) KiB)"
docs=()
[ -n "${FATHOM_SCENE_DOCS:-}" ] && docs=(docs/img)
FATHOM_NODE_MODULES="$work/node_modules" CHROMIUM="$CHROMIUM" \
  node .ci/scene-page.cjs "$page" "$work" "${docs[@]}"

# Negative controls: the same test on sabotaged copies of the page must fail (a page
# that draws nothing; a page that logs an error; a page whose modes never switch), or
# the checks above prove nothing.
control() {
  local name=$1 want=$2 copy="$work/control-$1.html"
  shift 2
  "$@" <"$page" >"$copy"
  if FATHOM_NODE_MODULES="$work/node_modules" CHROMIUM="$CHROMIUM" \
    node .ci/scene-page.cjs "$copy" "$work/control-$name" >"$work/control-$name.log" 2>&1; then
    echo "negative control '$name' passed the test: the test cannot fail" >&2
    exit 1
  fi
  grep -q "$want" "$work/control-$name.log" || {
    echo "negative control '$name' failed for another reason:" >&2
    cat "$work/control-$name.log" >&2
    exit 1
  }
  echo "negative control '$name': refused ($want)"
}
control blank "looks blank" sed 's/renderer.render(scene3, camera);/renderer.clear();/'
control console-error "console error" sed 's|</body>|<script>console.error("planted")</script></body>|'
control no-switch "never enters the map-aided mode" sed 's/mode: arr(m.mode)/mode: new Uint8Array(m.mode.n)/'

echo "scene page in Chromium: OK in $(($(date +%s) - start)) s"
