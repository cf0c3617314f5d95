#!/usr/bin/env bash
# ab_insert.sh REV [THREADS] [PAIRS] [RES] [DATA]: the working tree's insertion against REV's,
# in one process, alternating (see bench/ab_insert.cpp). Run from the repository root.
#   THREADS 1, PAIRS 20, RES 0.05, DATA ../shared/data/tum_fr2_pioneer_slam2 by default (or
#   build/data/scan.dat, which bench_insert decompresses on its first run).
# AB_FLAGS (environment) adds compiler flags, e.g. the AVX2 walks on an AVX-512 machine:
# AB_FLAGS="-DKNNOCC_NO_AVX512 -DKNNOCC_OLD_NO_AVX512" (REV's macros are renamed, see below).
# REV's headers go to build/ab/old/knnocc_old with namespace knnocc and the KNNOCC_ macros
# renamed, so that both versions live in one binary; it is compiled as the Release build
# (-O3 -DNDEBUG).
set -euo pipefail
rev=${1:?usage: bench/ab_insert.sh REV [THREADS] [PAIRS] [RES] [DATA]}
threads=${2:-1}
pairs=${3:-20}
res=${4:-0.05}
data=${5:-../shared/data/tum_fr2_pioneer_slam2}
out=build/ab
rm -rf "$out/old"
mkdir -p "$out/old"
git archive "$rev" include/knnocc | tar -x -C "$out/old"
mv "$out/old/include/knnocc" "$out/old/knnocc_old"
rmdir "$out/old/include"
find "$out/old/knnocc_old" -name '*.hpp' -exec sed -i \
  -e 's/namespace knnocc\b/namespace knnocc_old/g' -e 's/knnocc::/knnocc_old::/g' \
  -e 's/KNNOCC_/KNNOCC_OLD_/g' {} +
"${CXX:-g++}" -std=c++17 -O3 -DNDEBUG ${AB_FLAGS:-} -Iinclude -I"$out/old" $(pkg-config --cflags eigen3) \
  bench/ab_insert.cpp -o "$out/ab_insert" -pthread
"$out/ab_insert" "$threads" "$pairs" "$res" "$data"
