#!/usr/bin/env bash
# Renders a fixed list of small images (scenes x settings, fixed seed) with two candela binaries
# and compares their pixels exactly (idiff -fail 0): a change that means to leave images alone
# must pass. Usage:
#   tools/bit_identity.sh REFERENCE_BINARY NEW_BINARY [WORK_DIR]
# Run from the repository root (the CS184 scenes are read from ../shared/scenes/cs184).
# The renders are kept in WORK_DIR/<checksum of the binary and its image module>/ and reused.
set -euo pipefail

if [[ $# -lt 2 ]]; then
    sed -n '2,7p' "$0" >&2
    exit 2
fi
ref_bin=$1
new_bin=$2
work=${3:-${TMPDIR:-/tmp}/candela-bit-identity}
: "${BIT_IDENTITY_THREADS:=2}"

scenes=(
    ../shared/scenes/cs184/CBbunny.dae
    ../shared/scenes/cs184/CBspheres.dae
    ../shared/scenes/cs184/CBspheres_lambertian.dae
    ../shared/scenes/cs184/CBgems.dae
    scenes/cornell-box.dae
    scenes/glossy.dae
    scenes/mirror-coil.dae
    scenes/glass.dae
    scenes/lights.dae
)
# name|flags
settings=(
    "default|"
    "uniform|--adaptive none"
    "hemisphere|-H"
    "direct|--integrator direct"
    "light4|-l 4"
    "independent|--sampler independent"
    "lens|-b 0.08 -d 3.5"
    "cs184|-a 32 0.05"
    "normals|--integrator normals"
    "m1o0|-m 1 -o 0"
)
common=(-r 64 48 -s 32 --seed 7 -t "$BIT_IDENTITY_THREADS" -q)

render_all() { # binary dir
    local bin=$1 dir=$2
    mkdir -p "$dir"
    for scene in "${scenes[@]}"; do
        [[ -f $scene ]] || { echo "missing scene $scene (skipped)" >&2; continue; }
        for entry in "${settings[@]}"; do
            local name=${entry%%|*} flags=${entry#*|}
            local out="$dir/$(basename "$scene" .dae)-$name.exr"
            [[ -f $out ]] && continue
            # shellcheck disable=SC2086
            "$bin" render "$scene" "${common[@]}" $flags -f "$out.tmp.exr"
            mv "$out.tmp.exr" "$out"
        done
    done
}

# A binary's renders are keyed by its checksum and its image module's (beside it; it writes them).
key() { # binary
    local module
    module="$(dirname "$1")/libcandela_image.so"
    { sha1sum "$1"; if [[ -f $module ]]; then sha1sum "$module"; fi; } | cut -d' ' -f1 | sha1sum |
        cut -c1-12
}
ref_dir="$work/$(key "$ref_bin")"
new_dir="$work/$(key "$new_bin")"
render_all "$ref_bin" "$ref_dir"
render_all "$new_bin" "$new_dir"

same=0
differ=0
for ref in "$ref_dir"/*.exr; do
    new="$new_dir/$(basename "$ref")"
    if idiff -q -fail 0 -warn 0 "$ref" "$new" >/dev/null 2>&1; then
        same=$((same + 1))
    else
        differ=$((differ + 1))
        echo "DIFFERS: $(basename "$ref")"
    fi
done
echo "bit identity: $same identical, $differ different ($ref_dir vs $new_dir)"
[[ $differ -eq 0 ]]
