#!/usr/bin/env bash
# Renders the README gallery (docs/images/*.png) from the shared CS184 scenes and candela's own.
#   bash tools/render_gallery.sh [path/to/candela] [spp]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
candela="${1:-$root/build/candela}"
spp="${2:-256}"
shared="$root/../shared/scenes/cs184"
out="$root/docs/images"
mkdir -p "$out"

render() { # name scene [extra flags...]
    local name="$1" scene="$2"
    shift 2
    echo "gallery: $name" >&2
    "$candela" render "$scene" -r 320 240 -s "$spp" -m 8 -q -f "$out/$name.png" "$@"
    rm -f "$out/${name}_rate.png"
}

render cornell-box "$root/scenes/cornell-box.dae"
render materials "$root/scenes/materials.dae" --camera=file
render lights "$root/scenes/lights.dae" --camera=file
render glossy "$root/scenes/glossy.dae" --camera=file
render glass "$root/scenes/glass.dae" --camera=file
render CBspheres_lambertian "$shared/CBspheres_lambertian.dae"
render CBspheres "$shared/CBspheres.dae"
render CBbunny "$shared/CBbunny.dae"
render CBgems "$shared/CBgems.dae"
render CBempty "$shared/CBempty.dae"
render bunny "$shared/bunny.dae"
spp=4 render CBbunny_normals "$shared/CBbunny.dae" --integrator=normals
