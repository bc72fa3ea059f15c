#!/usr/bin/env bash
# Run the test suite of a build under other BLAS and LAPACK kernels than this machine's default,
# to find bounds that hold only for one machine's rounding (each test's bound must follow from
# the numerics with a tenfold margin; another CPU or BLAS changes the order of the sums).
#
#   bash scripts/check_portability.sh [build-dir] [ctest options...]
#
# Variants: OpenBLAS's kernels that this CPU can run (OPENBLAS_CORETYPE: Prescott for SSE3,
# Sandybridge for AVX, Haswell and Zen for AVX2 with FMA, SkylakeX for AVX-512), then the
# reference BLAS and LAPACK where Debian's libblas3 and liblapack3 are installed (taken ahead of
# the alternatives' OpenBLAS by LD_LIBRARY_PATH). About 2.5 min per variant on 2 cores, Release.
# Prints one line per variant and exits non-zero when any failed; each variant's log is in
# <build-dir>/portability-<variant>.log.
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
if [[ ! -f "$build/CTestTestfile.cmake" ]]; then
  echo "check_portability: '$build' is not a configured build directory (cmake -S . -B $build" \
       "and cmake --build $build first)" >&2
  exit 2
fi
flags=$(grep -m1 '^flags' /proc/cpuinfo || true)
has() { [[ " $flags " == *" $1 "* ]]; }
variants=(Prescott)
has avx && variants+=(Sandybridge)
has avx2 && has fma && variants+=(Haswell Zen)
has avx512f && variants+=(SkylakeX)
multiarch=/usr/lib/x86_64-linux-gnu
[[ -f $multiarch/blas/libblas.so.3 && -f $multiarch/lapack/liblapack.so.3 ]] && \
  variants+=(reference)

failed=0
for v in "${variants[@]}"; do
  log="$build/portability-$v.log"
  if [[ $v == reference ]]; then
    env=(LD_LIBRARY_PATH="$multiarch/blas:$multiarch/lapack${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
  else
    env=(OPENBLAS_CORETYPE="$v")
  fi
  start=$SECONDS
  if (cd "$build" && env "${env[@]}" ctest -j "$(nproc)" --output-on-failure "$@") > "$log" 2>&1
  then
    echo "check_portability: $v: passed ($((SECONDS - start)) s)"
  else
    failed=1
    echo "check_portability: $v: FAILED ($((SECONDS - start)) s): $(grep -A20 \
      'tests FAILED' "$log" | grep -E '^\s+[0-9]+ - ' | tr -s ' ' | tr '\n' ';')"
    echo "  log: $log"
  fi
done
exit $failed
