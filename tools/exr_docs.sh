#!/usr/bin/env bash
# Remakes the examples of the documentation from candela's own scenes, in place:
#   docs/usage.md "What candela prints": what a default render of cornell-box prints (progress
#   lines left out), and the fingerprint line under it (the sample statistics of a 40x30
#   default render, which tests/app/docs_listing_test.cpp renders again: it fails when they
#   differ, that is when the renderer's images changed and this script must be run again);
#   docs/exr-metadata.md "A default render": `oiiotool --info -v` of that render;
#   docs/images/composite.png: a -p region render of cornell-spheres, composited with
#   `oiiotool --over` over a checkerboard plate of the full frame.
# The prose beside the listings (date, load average, wall time) is edited by hand from what
# this script prints.
#   bash tools/exr_docs.sh [path/to/candela]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
candela="${1:-$root/build/candela}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# Replaces the first ``` block after the line HEADING of FILE with the contents of NEW.
replace_block() {
    python3 - "$1" "$2" "$3" <<'PY'
import sys
path, heading, new = sys.argv[1], sys.argv[2], open(sys.argv[3]).read()
text = open(path).read()
h = text.index("\n" + heading + "\n")
start = text.index("```\n", h) + 4
end = text.index("```", start)
open(path, "w").write(text[:start] + new.rstrip("\n") + "\n" + text[end:])
PY
}

# The stats lines a fingerprint is made of, from a render's stderr.
fingerprint() {
    grep -E '^  (samples/pixel|stopped|samples) ' "$1" | sed 's/^ *//; s/  */ /g' |
        paste -sd'|' | sed 's/|/ | /g'
}

# A default render, in a directory whose scenes/ is the repository's, so that the recorded
# command line is the one a user types.
ln -s "$root/scenes" "$tmp/scenes"
(cd "$tmp" && "$candela" render scenes/cornell-box.dae 2>"$tmp/stderr.txt")
grep -v '^progress:' "$tmp/stderr.txt" >"$tmp/printed.txt" || true
echo "exr_docs: docs/usage.md \"What candela prints\" ($(date -u '+%d %B %Y %H:%M UTC'), load" \
    "average after the run:$(uptime | sed 's/.*load average://')):" >&2
cat "$tmp/printed.txt"
replace_block "$root/docs/usage.md" "## What candela prints" "$tmp/printed.txt"

(cd "$tmp" && "$candela" render scenes/cornell-box.dae -r 40 30 -f small.exr 2>"$tmp/small.txt")
line="<!-- exr_docs fingerprint (40x30): $(fingerprint "$tmp/small.txt") -->"
python3 - "$root/docs/usage.md" "$line" <<'PY'
import re, sys
path, line = sys.argv[1], sys.argv[2]
text = open(path).read()
text, n = re.subn(r"<!-- exr_docs fingerprint \(40x30\): .* -->", lambda m: line, text)
if n != 1:
    sys.exit("exr_docs: no fingerprint line in " + path)
open(path, "w").write(text)
PY
echo "exr_docs: $line" >&2

(cd "$tmp" && oiiotool --info -v cornell-box.exr) >"$tmp/info.txt"
echo "exr_docs: docs/exr-metadata.md's listing:" >&2
cat "$tmp/info.txt"
replace_block "$root/docs/exr-metadata.md" "## A default render" "$tmp/info.txt"

# A region (CS184 cell: x y dx dy from the bottom-left) of a 320x240 frame, over a plate.
"$candela" render "$root/scenes/cornell-spheres.dae" -r 320 240 -s 256 -p 40 30 240 180 -q \
    -f "$tmp/region.exr"
oiiotool --pattern checker:width=20:height=20:color1=0.05,0.06,0.09:color2=0.12,0.13,0.18 \
    320x240 3 --chnames R,G,B --ch R,G,B,A=1.0 -o "$tmp/plate.exr"
oiiotool "$tmp/region.exr" --ch R,G,B,A "$tmp/plate.exr" --over -o "$tmp/composite.exr"
oiiotool "$tmp/composite.exr" --ch R,G,B --colorconvert linear sRGB -d uint8 \
    -o "$root/docs/images/composite.png"
echo "exr_docs: wrote $root/docs/images/composite.png" >&2
