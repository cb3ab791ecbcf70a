#!/usr/bin/env bash
# granuflow's two entry points for a fresh Debian 12 / Ubuntu machine (see README.md):
#   ./run.sh main   install what is missing (apt-get), build (CMake, Release), run the main job into out/main
#   ./run.sh test   same setup, then lint (clang-format-14, flake8) and every test: GoogleTest (ctest), pytest,
#                   notebooks, and the sanitizer build (./run.sh sanitize)
# Also: ./run.sh setup | build | lint | bench | sanitize | fuzz scene|experiments|collisions [seconds]
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(cmake ninja-build g++ pkg-config
  libsundials-dev libeigen3-dev libceres-dev pybind11-dev libgtest-dev
  libyaml-cpp-dev libudunits2-dev graphviz chromium
  python3-dev python3-numpy python3-scipy python3-matplotlib python3-pandas python3-yaml python3-pytest
  python3-nbclient python3-nbformat python3-ipykernel jupyter-nbconvert python3-distributed python3-tqdm
  python3-nlopt clang-format-14 flake8)
# pip install of the checkout into a virtual environment (tests/python/test_install.py, docs/install_and_plugins.md).
PACKAGES+=(python3-pip python3-venv python3-setuptools python3-wheel)
# Checking builds (./run.sh sanitize, fuzz): Debian's clang and its libFuzzer/sanitizer runtimes.
PACKAGES+=(clang-14 libclang-rt-14-dev)
MAIN_SCENE=flowsheets/stoeckl_gf25_batch.yaml

setup() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "run.sh: installing ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
  fi
}

build() {
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DGRANUFLOW_BUILD_PYTHON=ON \
    -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
  cmake --build build -j "$(nproc)"
}

# Formatting and lint with Debian's tools: every C++ file against the committed .clang-format, and flake8 (config in
# .flake8) over the Python package and the tests.
lint() {
  git ls-files -z '*.cpp' '*.hpp' '*.h' '*.cc' | xargs -0 clang-format-14 --dry-run --Werror
  flake8 python/ tests/
  echo "lint: clang-format-14 and flake8 clean"
}

run_tests() {
  lint
  (cd build && ctest --output-on-failure -j "$(nproc)" -L fast)
  PYTHONPATH="$PWD/build/python" /usr/bin/python3 -m pytest -q tests/python
  sanitize  # ~5 min on 2 cores: ASan+UBSan C++ tests, headline scene, bounded fuzzing (tests/fuzz/README.md)
}

# AddressSanitizer + UndefinedBehaviorSanitizer build with the libFuzzer targets (clang, -O1, assertions on) in
# build-asan: every C++ test, the headline scene, a bounded run of each fuzz target and the replay of
# saved findings (tests/fuzz/README.md). Any sanitizer report fails its test.
sanitize_build() {
  CC=clang-14 CXX=clang++-14 cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DGRANUFLOW_BUILD_PYTHON=OFF -DGRANUFLOW_SANITIZE=ON -DGRANUFLOW_FUZZ=ON \
    -DGRANUFLOW_FUZZ_SECONDS="${GRANUFLOW_FUZZ_SECONDS:-5}" >/dev/null
  cmake --build build-asan -j "$(nproc)"
}
# LeakSanitizer skips only the units library's own leaks on unit texts it cannot parse (tests/fuzz/lsan_suppressions.txt).
LSAN_SUPPRESSIONS="suppressions=$PWD/tests/fuzz/lsan_suppressions.txt:print_suppressions=0"
sanitize() {
  sanitize_build
  (cd build-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    LSAN_OPTIONS="$LSAN_SUPPRESSIONS" ctest --output-on-failure -j "$(nproc)" -L 'fast|scene|fuzz')
}
# A longer fuzz run of one target: ./run.sh fuzz scene|experiments|collisions [seconds] (default 600).
fuzz() {
  local target="${1:-scene}" seconds="${2:-600}" seeds
  case "$target" in
    scene) seeds="flowsheets tests/fuzz/regressions/scene" ;;
    experiments) seeds="tests/fuzz/seeds/experiments tests/fuzz/regressions/experiments" ;;
    collisions) seeds="tests/fuzz/seeds/collisions tests/fuzz/regressions/collisions" ;;
    *) echo "usage: ./run.sh fuzz scene|experiments|collisions [seconds]" >&2; exit 2 ;;
  esac
  sanitize_build
  mkdir -p "build-asan/tests/fuzz/corpus/$target" build-asan/tests/fuzz/findings
  # shellcheck disable=SC2086
  LSAN_OPTIONS="$LSAN_SUPPRESSIONS" "build-asan/tests/fuzz/fuzz_$target" -rss_limit_mb=2048 -timeout=20 -max_len=16384 -max_total_time="$seconds" \
    -artifact_prefix=build-asan/tests/fuzz/findings/ "build-asan/tests/fuzz/corpus/$target" $seeds
}

case "${1:-}" in
  setup) setup ;;
  build) setup && build ;;
  lint) setup && lint ;;
  main) setup && build && ./build/granuflow run "$MAIN_SCENE" --out out/main ;;
  test) setup && build && run_tests ;;
  bench) setup && build && ./build/granuflow bench core && ./build/granuflow bench pbm ;;
  sanitize) setup && sanitize ;;
  fuzz) setup && fuzz "${2:-scene}" "${3:-600}" ;;
  *) echo "usage: ./run.sh main|test|setup|build|lint|bench|sanitize|fuzz" >&2; exit 2 ;;
esac
