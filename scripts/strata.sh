#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (as root, or with sudo):
#   bash scripts/strata.sh crowd [strata crowd options]   install what is missing, build, run the main job
#   bash scripts/strata.sh test                           install what is missing, build, run the tests
#   bash scripts/strata.sh build                          install what is missing, build
#   bash scripts/strata.sh validate-gltf                  export the walker at every body level and run the Khronos
#                                                         glTF validator on the files (fails on any error)
# Environment: BUILD_DIR (default build), JOBS (default: all cores).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
JOBS="${JOBS:-$(nproc)}"

# Debian 12 packages the build, the tests and headless rendering need. xvfb/xauth only serve the windowed
# viewer's smoke test; Mesa's llvmpipe (libgl1-mesa-dri, libegl-mesa0) renders headless through EGL. ffmpeg
# (27 MB with --no-install-recommends) lets `strata crowd` write crowd.mp4 and the tests check it.
PACKAGES=(
  cmake ninja-build g++ pkg-config
  libglm-dev libglfw3-dev libosd-dev libtinygltf-dev libopenimageio-dev
  libgl-dev libegl-dev libgl1-mesa-dri libegl-mesa0 libepoxy-dev
  libpugixml-dev libtbb-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libbenchmark-dev libmeshoptimizer-dev
  xvfb xauth
  ffmpeg
)

install_missing() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "strata.sh: installing ${missing[*]}" >&2
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

build() {
  cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

# The Khronos validator is an npm package (Dart compiled to JavaScript) run under Node.js. It goes into the build
# directory (npm install --prefix), pinned, so the repository and the system's Node modules stay untouched.
GLTF_VALIDATOR_VERSION=2.0.0-dev.3.10
validate_gltf() {
  local prefix="$BUILD_DIR/gltf-validator"
  if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    echo "strata.sh: installing nodejs npm for the glTF validator" >&2
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
  fi
  if [ ! -f "$prefix/node_modules/gltf-validator/package.json" ]; then
    npm install --prefix "$prefix" --no-audit --no-fund --loglevel=error "gltf-validator@$GLTF_VALIDATOR_VERSION" >&2
  fi
  local out="$BUILD_DIR/validate-gltf"
  mkdir -p "$out"
  local files=()
  for level in 0 1 2; do
    "$BUILD_DIR/strata" export --format gltf --level "$level" --seconds 2 --out "$out/walker_level$level.glb"
    files+=("$out/walker_level$level.glb")
  done
  node "$ROOT/scripts/validate_gltf.js" "$prefix" "${files[@]}"
}

cmd="${1:-}"
[ $# -gt 0 ] && shift
case "$cmd" in
  crowd)
    install_missing
    build
    cd "$ROOT"
    "$BUILD_DIR/strata" crowd "$@"
    ;;
  test)
    install_missing
    build
    cd "$BUILD_DIR"
    # Tests render through EGL surfaceless; a stray DISPLAY must not matter, so make it absent as in CI.
    env -u DISPLAY ctest --output-on-failure -j "$JOBS" "$@"
    ;;
  build)
    install_missing
    build
    ;;
  validate-gltf)
    install_missing
    build
    validate_gltf
    ;;
  *)
    echo "usage: bash scripts/strata.sh crowd|test|build|validate-gltf [args]" >&2
    exit 2
    ;;
esac
