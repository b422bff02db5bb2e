#!/usr/bin/env bash
# One-command set-up for a fresh Debian bookworm machine (run as root, or with sudo available).
#   bash tools/bootstrap.sh render   install what is missing, build, render a quick preview of
#                                    the default scene and say what a full-quality one costs
#   bash tools/bootstrap.sh test     install what is missing, build, run every test; then build
#                                    the MPI variants of candela and of the test binary in the
#                                    same build dir and run the [mpi] tests with them; last, build
#                                    the scene loader's fuzz target
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
# The test command also builds the scene loader's libFuzzer target (tools/fuzz.sh build).
if [ "$mode" = test ]; then packages+=(clang libclang-rt-14-dev); fi
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
configure_log="$(mktemp)"
trap 'rm -f "$configure_log"' EXIT
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCANDELA_WERROR="$werror" 2>&1 |
    tee "$configure_log"
if [ "$mode" = test ] && grep -q "references the file" "$configure_log"; then
    # A dependency's CMake files reporting a file of theirs missing (Imath's PyImath on
    # bookworm) are held back by cmake/CandelaDeps.cmake; one in the log is a new such block.
    echo "bootstrap: the configure step printed a dependency's missing-file block" >&2
    exit 1
fi
if [ "$mode" = render ]; then
    cmake --build "$build" -j "$jobs" --target candela
else
    cmake --build "$build" -j "$jobs"
fi

if [ "$mode" = render ]; then
    mkdir -p "$root/out"
    # A preview: a quarter of the default frame at a 64-sample budget (seconds on 2 cores),
    # as an HDR EXR and as a PNG that any image viewer opens.
    "$build/candela" render "$root/scenes/cornell-box.dae" -r 400 300 -s 64 \
        -f "$root/out/cornell-box.exr" --preview
    echo "bootstrap: full quality is the default command, 800x600 to a noise of 2 % or a budget"
    echo "  of 1024 samples per pixel: $build/candela render scenes/cornell-box.dae"
    echo "  (about 4 minutes on 2 cores; what it prints and took: docs/usage.md"
    echo "  \"What candela prints\")"
    echo "bootstrap: wrote a 400x300 preview render:"
    echo "  $root/out/cornell-box.png (PNG: open it with any image viewer)"
    echo "  $root/out/cornell-box.exr (HDR EXR with alpha, depth and more: tev, oiiotool, GIMP)"
    echo "  and $root/out/cornell-box_rate.png (samples per pixel: blue few, red many)"
else
    (cd "$build" && ctest --output-on-failure -j "$jobs")
    # The default build has no MPI; its MPI variants exercise distributed rendering (mpirun over
    # loopback). They share every object file but the distributed unit, the MPI tests and the
    # two mains with the build above (CMakeLists.txt: candela_mpi).
    cmake --build "$build" -j "$jobs" --target candela_tests_mpi
    mpi_log="$build/mpi-tests.log"
    "$build/tests/candela_tests_mpi" "[mpi]" 2>&1 | tee "$mpi_log"
    # The test that makes ranks fail keeps mpirun's banner about them out of the log.
    if grep -q "mpirun detected\|Primary job" "$mpi_log"; then
        echo "bootstrap: a passing [mpi] run printed mpirun's failure banner ($mpi_log)" >&2
        exit 1
    fi
    # The fuzz target is built (not run) so that it cannot stop building unnoticed.
    CANDELA_FUZZ_BUILD="${CANDELA_FUZZ_BUILD:-$build-fuzz}" bash "$root/tools/fuzz.sh" build
fi
