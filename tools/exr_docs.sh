#!/usr/bin/env bash
# Remakes the examples of the documentation from candela's own scenes:
#   README.md's "What candela prints": what a default render of cornell-box prints (progress
#   lines left out), with the load average it ran at;
#   docs/exr-metadata.md's listing: `oiiotool --info -v` of that render;
#   docs/images/composite.png: a -p region render of cornell-spheres, composited with
#   `oiiotool --over` over a checkerboard plate of the full frame.
#   bash tools/exr_docs.sh [path/to/candela]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
candela="${1:-$root/build/candela}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# A default render, in a directory whose scenes/ is the repository's, so that the recorded
# command line is the one a user types.
ln -s "$root/scenes" "$tmp/scenes"
# tests/app/docs_listing_test.cpp fails when either listing no longer matches the defaults.
(cd "$tmp" && "$candela" render scenes/cornell-box.dae 2>"$tmp/stderr.txt")
grep -v '^progress:' "$tmp/stderr.txt" >"$tmp/printed.txt" || true
echo "exr_docs: README \"What candela prints\" (load average after the run:$(uptime |
    sed 's/.*load average://')):" >&2
cat "$tmp/printed.txt"
(cd "$tmp" && oiiotool --info -v cornell-box.exr) >"$tmp/info.txt"
echo "exr_docs: docs/exr-metadata.md's listing:" >&2
cat "$tmp/info.txt"

# A region (CS184 cell: x y dx dy from the bottom-left) of a 320x240 frame, over a plate.
"$candela" render "$root/scenes/cornell-spheres.dae" -r 320 240 -s 256 -p 40 30 240 180 -q \
    -f "$tmp/region.exr"
oiiotool --pattern checker:width=20:height=20:color1=0.05,0.06,0.09:color2=0.12,0.13,0.18 \
    320x240 3 --chnames R,G,B --ch R,G,B,A=1.0 -o "$tmp/plate.exr"
oiiotool "$tmp/region.exr" --ch R,G,B,A "$tmp/plate.exr" --over -o "$tmp/composite.exr"
oiiotool "$tmp/composite.exr" --ch R,G,B --colorconvert linear sRGB -d uint8 \
    -o "$root/docs/images/composite.png"
echo "exr_docs: wrote $root/docs/images/composite.png" >&2
