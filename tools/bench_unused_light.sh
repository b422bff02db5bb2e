#!/usr/bin/env bash
# Shows that a feature a scene does not use costs nothing: CBspheres_lambertian with and
# without an extra ambient light of zero radiance. The builder drops the dark light, so both
# renders run the same code and must produce bit-identical pixels in (nearly) the same time.
#   bash tools/bench_unused_light.sh [path/to/candela] [repeats]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
candela="${1:-$root/build/candela}"
repeats="${2:-3}"
scene="$root/../shared/scenes/cs184/CBspheres_lambertian.dae"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# The same scene plus <light id="Dark"> (ambient, colour 0) instanced by a node.
sed -e 's|<library_lights>|<library_lights><light id="Dark-light" name="Dark"><technique_common><ambient><color>0 0 0</color></ambient></technique_common></light>|' \
    -e 's|<visual_scene id="Scene" name="Scene">|<visual_scene id="Scene" name="Scene"><node id="Dark" name="Dark"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_light url="#Dark-light"/></node>|' \
    "$scene" > "$tmp/with-dark-light.dae"
grep -q 'Dark-light' "$tmp/with-dark-light.dae"

args=(-r 160 120 -s 32 -m 8 -t 1 --aov none --seed 1)
for i in $(seq "$repeats"); do
    for variant in plain dark; do
        src="$scene"
        [ "$variant" = dark ] && src="$tmp/with-dark-light.dae"
        secs=$("$candela" render "$src" "${args[@]}" -f "$tmp/$variant.exr" 2>&1 |
            sed -n 's/^summary: \([0-9.]*\) s wall.*/\1/p')
        echo "run $i $variant: $secs s"
    done
done
same=$(idiff -fail 0 -warn 0 -a "$tmp/plain.exr" "$tmp/dark.exr" >/dev/null 2>&1 && echo yes || echo no)
echo "pixels identical: $same"
