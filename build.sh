#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine:
#   ./build.sh demo   install packages, build, render the built-in demo into out/demo
#   ./build.sh test   install packages, build, run every test
#   ./build.sh build  install packages and build only
#   ./build.sh sanitize          build into build-sanitize with clang, AddressSanitizer and
#                                UndefinedBehaviorSanitizer, and run the sanitized subset of
#                                the tests there (docs/development/ci.md says which and why)
#   ./build.sh fuzz [SECONDS]    build the parsers' libFuzzer targets in the same folder and
#                                fuzz each for SECONDS (default 60) from its corpus
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(build-essential cmake ninja-build pkg-config
          libopenimageio-dev openimageio-tools libopencolorio-dev opencolorio-tools libopenexr-dev
          libglm-dev catch2 nlohmann-json3-dev libcli11-dev libfmt-dev fonts-dejavu-core
          pybind11-dev python3-dev python3-numpy python3-openimageio python3-venv python3-jsonschema)
# clang and its runtime libraries (libFuzzer, the sanitizers) for the sanitized build.
SANITIZE_PACKAGES=(clang libclang-rt-14-dev)
FUZZ_TARGETS=(fuzz_stock fuzz_look fuzz_grain_profile)
# The sanitized subset: the model's own tests (core), the look layer, the plugin in a host,
# and the parsers' corpora; the program's tests (cli) run its file I/O through OpenImageIO,
# whose code is not ours, and take the most time. Left out too: three long statistical tests
# whose code the others cover (every stock's sensitometry, a large plate analysis, renders
# repeated on many thread counts).
SANITIZED_TARGETS=(test_core test_look test_plugin replay_stock replay_look replay_grain_profile)
SANITIZED_TESTS="^(core|look|plugin|fuzz corpus):"
SANITIZED_SKIPPED="every built-in stock measures|grain analysed from a plate matches|any thread count and window"
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
# The data sheets' curves, spektrafilm's profiles and the real film scans that some tests
# check against lie beside the project (tests/CMakeLists.txt); where they are missing those
# tests pass without their checks, which a run should say.
REFERENCE_DATA=../shared/reference-data

install_packages() {
  local missing=()
  for p in "${PACKAGES[@]}" "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
  done
  ((${#missing[@]} == 0)) && return
  echo "Installing Debian packages: ${missing[*]}"
  local sudo=()
  [[ $(id -u) -eq 0 ]] || sudo=(sudo)
  "${sudo[@]}" apt-get update
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
}

build() {
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release ${CCACHE:+-DCMAKE_CXX_COMPILER_LAUNCHER=ccache} "$@"
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

# One clang build serves the sanitized tests and the fuzzers: every library with
# AddressSanitizer, UndefinedBehaviorSanitizer and libFuzzer's coverage (DARKROOM_FUZZ),
# without the Python module (Debian's python3 cannot load a sanitized one).
configure_sanitized() {
  CC=clang CXX=clang++ cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=Release -DDARKROOM_FUZZ=ON \
    ${CCACHE:+-DCMAKE_CXX_COMPILER_LAUNCHER=ccache}
}

# Any sanitizer report fails the run: UB aborts (-fno-sanitize-recover=all), leaks count.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

note_reference_data() {
    [[ -d "$REFERENCE_DATA" ]] ||
        echo "note: no $REFERENCE_DATA beside the project: the tests against the data sheets," \
             "spektrafilm's profiles and the real film scans ran without those checks" >&2
}

case "${1:-}" in
  demo)
    install_packages
    build
    "$BUILD_DIR/cli/darkroom" demo -o out/demo -v
    ;;
  test)
    install_packages
    build
    ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS"
    note_reference_data
    ;;
  build)
    install_packages
    build
    ;;
  sanitize)
    install_packages "${SANITIZE_PACKAGES[@]}"
    configure_sanitized
    cmake --build build-sanitize -j "$JOBS" --target "${SANITIZED_TARGETS[@]}"
    ctest --test-dir build-sanitize --output-on-failure -j "$JOBS" -R "$SANITIZED_TESTS" -E "$SANITIZED_SKIPPED"
    note_reference_data
    ;;
  fuzz)
    seconds=${2:-60}
    install_packages "${SANITIZE_PACKAGES[@]}"
    configure_sanitized
    cmake --build build-sanitize -j "$JOBS" --target "${FUZZ_TARGETS[@]}"
    for target in "${FUZZ_TARGETS[@]}"; do
      corpus=tests/fuzz/corpus/${target#fuzz_}
      # New inputs go to a scratch folder; the kept corpus changes only by hand (see tests/fuzz/README.md).
      rm -rf "build-sanitize/new-corpus/$target" && mkdir -p "build-sanitize/new-corpus/$target"
      echo "== $target: ${seconds} s from $corpus"
      # (-timeout: an accepted input is rendered, which a look of a film frame a few um wide
      # makes slow under the sanitizers, with halation kernels of thousands of pixels)
      "build-sanitize/tests/fuzz/$target" -max_total_time="$seconds" -timeout=60 -rss_limit_mb=2048 \
        -dict=tests/fuzz/json.dict -artifact_prefix="build-sanitize/$target-" -print_final_stats=1 \
        "build-sanitize/new-corpus/$target" "$corpus"
    done
    ;;
  *)
    echo "usage: $0 demo|test|build|sanitize|fuzz [seconds]" >&2
    exit 2
    ;;
esac
