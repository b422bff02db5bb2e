#!/usr/bin/env bash
# One-command set-up for a fresh Debian bookworm machine (run as root, or with sudo available).
#   bash tools/bootstrap.sh render   install what is missing, build, render a quick preview of
#                                    the default scene and say what a full-quality one costs
#   bash tools/bootstrap.sh test     install what is missing, build, run every test; then build
#                                    a second, MPI-enabled binary and run the [mpi] tests with it
# Safe to run again: installed packages are skipped and the build is incremental.
set -euo pipefail

mode="${1:-render}"
case "$mode" in render | test) ;; *)
    echo "usage: bash tools/bootstrap.sh render|test" >&2
    exit 2
    ;;
esac

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${CANDELA_BUILD_DIR:-$root/build}"
jobs="$(nproc 2>/dev/null || echo 2)"

packages=(
    build-essential cmake pkg-config
    libembree-dev libopenimageio-dev openimageio-tools libopenexr-dev libtinyxml2-dev
    catch2 libtbb-dev libcli11-dev libfmt-dev nlohmann-json3-dev
    libopenmpi-dev openmpi-bin
)
missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done
if [ "${#missing[@]}" -gt 0 ]; then
    echo "bootstrap: installing ${missing[*]}"
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

werror=OFF
if [ -n "${CI:-}" ]; then werror=ON; fi
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCANDELA_WERROR="$werror"
if [ "$mode" = render ]; then
    cmake --build "$build" -j "$jobs" --target candela
else
    cmake --build "$build" -j "$jobs"
fi

if [ "$mode" = render ]; then
    mkdir -p "$root/out"
    # A preview: a quarter of the default frame at a 64-sample budget (seconds on 2 cores).
    "$build/candela" render "$root/scenes/cornell-box.dae" -r 400 300 -s 64 \
        -f "$root/out/cornell-box.exr"
    echo "bootstrap: wrote $root/out/cornell-box.exr (a 400x300 preview)"
    echo "bootstrap: full quality is the default command, 800x600 to a noise of 2 % or a budget"
    echo "  of 1024 samples per pixel: $build/candela render scenes/cornell-box.dae"
    echo "  (about 4 minutes on 2 cores; what it prints and took: docs/usage.md"
    echo "  \"What candela prints\")"
else
    (cd "$build" && ctest --output-on-failure -j "$jobs")
    # The default build has no MPI; a second build dir exercises distributed rendering
    # (mpirun over loopback). Only the test binary and candela are built there.
    build_mpi="${CANDELA_MPI_BUILD_DIR:-$build-mpi}"
    cmake -S "$root" -B "$build_mpi" -DCMAKE_BUILD_TYPE=Release -DCANDELA_WERROR="$werror" \
        -DCANDELA_WITH_MPI=ON
    cmake --build "$build_mpi" -j "$jobs" --target candela_tests
    "$build_mpi/tests/candela_tests" "[mpi]"
fi
