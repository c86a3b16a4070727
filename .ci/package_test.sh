#!/usr/bin/env bash
# The engine as a package (issue 16): configure the engine alone with every peer engine, fmt,
# Google Benchmark and GoogleTest hidden from CMake (so it provably needs none of them), build
# and install it into a temporary prefix, then build examples/falling_ball.cpp against that
# prefix twice, with find_package(quadrant CONFIG) and with pkg-config, and run both; then the
# adapters library with every peer switched off (each peer adapter is optional).
# 32 s of CPU (77 s wall at load average 14 on the shared 2-core VM; the engine build alone took 20 s idle).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
WORK="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-package.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT

hidden=()
for pkg in box2d fmt benchmark GTest PkgConfig OpenMP MPI; do
  hidden+=("-DCMAKE_DISABLE_FIND_PACKAGE_${pkg}=ON")
done
echo "-- engine-only configure (peers, fmt, benchmark, GTest, MPI hidden)"
cmake --no-warn-unused-cli -S "$ROOT" -B "$WORK/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DQUADRANT_WERROR=ON \
  -DQUADRANT_BUILD_TESTS=OFF -DQUADRANT_BUILD_BENCHMARKS=OFF "${hidden[@]}" >"$WORK/configure.log" \
  || { cat "$WORK/configure.log"; exit 1; }
cmake --build "$WORK/build" -j 2 >"$WORK/build.log" || { tail -n 30 "$WORK/build.log"; exit 1; }
cmake --install "$WORK/build" --prefix "$WORK/prefix" >/dev/null

echo "-- examples/ with find_package(quadrant CONFIG)"
cmake -S "$ROOT/examples" -B "$WORK/example" -G Ninja -DCMAKE_PREFIX_PATH="$WORK/prefix" >/dev/null
cmake --build "$WORK/example" >/dev/null
"$WORK/example/falling_ball"

echo "-- examples/falling_ball.cpp with pkg-config"
export PKG_CONFIG_PATH="$WORK/prefix/lib/pkgconfig"
# shellcheck disable=SC2046  # pkg-config's output is a list of words
g++ "$ROOT/examples/falling_ball.cpp" $(pkg-config --cflags --libs quadrant) -o "$WORK/falling_ball_pc"
"$WORK/falling_ball_pc"
echo "-- the adapters with no peer engine (QUADRANT_WITH_<PEER>=OFF): only the Quadrant adapter"
unhidden=()  # fmt and Google Benchmark are needed now; the peers stay off by option
for pkg in fmt benchmark PkgConfig OpenMP; do
  unhidden+=("-DCMAKE_DISABLE_FIND_PACKAGE_${pkg}=OFF")
done
cmake --no-warn-unused-cli -S "$ROOT" -B "$WORK/build" -DQUADRANT_BUILD_BENCHMARKS=ON "${unhidden[@]}" \
  -DQUADRANT_WITH_BOX2D=OFF -DQUADRANT_WITH_BULLET=OFF -DQUADRANT_WITH_CHIPMUNK=OFF >"$WORK/configure2.log" \
  || { cat "$WORK/configure2.log"; exit 1; }
grep -q "peer adapters built: ; not built: box2d;bullet;chipmunk" "$WORK/configure2.log" \
  || { echo "FAIL: the peers were not left out"; cat "$WORK/configure2.log"; exit 1; }
cmake --build "$WORK/build" -j 2 --target quadrant_adapters >"$WORK/build2.log" || { tail -n 30 "$WORK/build2.log"; exit 1; }
echo "-- package test passed"
