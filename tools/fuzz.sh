#!/usr/bin/env bash
# Builds (if needed) and runs the libFuzzer target for the scene loader.
#
#   tools/fuzz.sh SECONDS [extra libFuzzer flags...]
#   tools/fuzz.sh build       configure and build the target only (the test command does this,
#                             so the fuzz build cannot rot unnoticed)
#
# Run from anywhere; paths are relative to the repository root. Environment:
#   CANDELA_FUZZ_BUILD   build directory              (default: <repo>/build-fuzz)
#   CANDELA_FUZZ_CORPUS  working corpus, outside repo (default: ${TMPDIR:-/tmp}/candela-fuzz-corpus)
#   CANDELA_FUZZ_FORK    1 = keep going after a finding (-fork=1 -ignore_crashes=1 ...)
#   CXX                  clang++ to use               (default: clang++-14, else clang++)
set -euo pipefail

if [[ $# -lt 1 || ! ($1 =~ ^[0-9]+$ || $1 == build) ]]; then
    echo "usage: $0 SECONDS [libFuzzer flags...] | $0 build" >&2
    exit 2
fi
seconds=$1
shift

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${CANDELA_FUZZ_BUILD:-$root/build-fuzz}
tmp=${TMPDIR:-/tmp}
corpus=${CANDELA_FUZZ_CORPUS:-$tmp/candela-fuzz-corpus}
seeds=$tmp/candela-fuzz-seeds
artifacts=$tmp/candela-fuzz-artifacts
# Seeds larger than this are skipped: big meshes slow every execution and add no new structure.
seed_max_bytes=65536

if [[ -z ${CXX:-} ]]; then
    if command -v clang++-14 >/dev/null; then CXX=clang++-14; else CXX=clang++; fi
fi

# Configure once, then let the (incremental) build decide what is stale.
# The build's output is kept quiet unless it fails.
mkdir -p "$build"
log=$build/fuzz-build.log
if ! { [[ -f $build/CMakeCache.txt ]] ||
    CXX=$CXX cmake -S "$root/tools/fuzz" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo; } >"$log" 2>&1 ||
    ! cmake --build "$build" -j"${CANDELA_FUZZ_JOBS:-2}" >>"$log" 2>&1; then
    cat "$log" >&2
    echo "fuzz: the build failed (log above, also in $log)" >&2
    exit 1
fi
if [[ $seconds == build ]]; then
    echo "fuzz: built $build/fuzz_loader" >&2
    exit 0
fi

mkdir -p "$corpus" "$seeds" "$artifacts"
# Seeds: the shared course scenes (small ones), the repo's example scenes and the broken-file
# and fuzz regression corpora. Copied so that libFuzzer never writes into the repository.
shopt -s nullglob
for f in "$root"/../shared/scenes/cs184/*.dae "$root"/scenes/*.dae "$root"/tests/data/broken/*.dae \
    "$root"/tests/data/fuzz/*; do
    if [[ $(stat -c %s "$f") -le $seed_max_bytes ]]; then
        cp -f "$f" "$seeds/"
    fi
done

flags=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="$seed_max_bytes"
    -dict="$root/tools/fuzz/collada.dict" -close_fd_mask=2 -print_final_stats=1
    -artifact_prefix="$artifacts/")
if [[ ${CANDELA_FUZZ_FORK:-0} == 1 ]]; then
    flags+=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
fi
echo "corpus: $corpus  artifacts: $artifacts" >&2
exec "$build/fuzz_loader" "${flags[@]}" "$@" "$corpus" "$seeds"
