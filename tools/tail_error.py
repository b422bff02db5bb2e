#!/usr/bin/env python3
"""Where the squared error of a render sits: its relMSE against a reference, the relMSE left
when the worst 1 % of pixels are set aside, and the share of the squared error those pixels
(and the worst 0.1 %) carry. Fireflies (single samples of large weight) put most of the error
in a few pixels; noise spread evenly does not.

    tools/tail_error.py REFERENCE.exr RENDER.exr [RENDER.exr ...]
    tools/tail_error.py REFERENCE.exr --pairs A.exr,B.exr [C.exr,D.exr ...]
    tools/tail_error.py --copper-bunny OUT.dae

A pixel's error is the mean over RGB of (x - r)^2 / (r^2 + 0.01), the relMSE measure of
`candela converge` and tools/compare_cycles.py (whose image reader this uses: oiiotool).

--pairs measures noise alone, without the reference's own noise or any difference of models
between renderers: for two renders of one renderer with independent seeds, half of the mean of
(a - b)^2 / (r^2 + 0.01) is the relMSE of one of them against its own converged mean (the
reference only scales the pixels). The shares are those of the pixels of (a - b)^2.

--copper-bunny writes ../shared/scenes/cs184/CBbunny.dae with the bunny's material replaced by
the CS184 copper microfacet conductor (alpha 0.05, the eta and k of
CBbunny_microfacet_cu.dae), for the per-sample error figures of docs/performance.md. Write it
outside the repository: the course scenes are not copied into it.
"""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare_cycles  # noqa: E402  (its image reader and relMSE offset)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CBBUNNY = os.path.join(ROOT, "..", "shared", "scenes", "cs184", "CBbunny.dae")
COPPER = """
      <extra>
        <technique profile="CGL">
          <microfacet>
            <alpha>0.05</alpha>
            <eta>0.33228 1.0162 1.2474</eta>
            <k>3.1646 2.5785 2.4603</k>
          </microfacet>
        </technique>
      </extra>"""


def copper_bunny(out):
    with open(CBBUNNY) as f:
        text = f.read()
    start = text.index('<effect id="Default-effect">')  # the bunny's effect
    end = text.index("</profile_COMMON>", start) + len("</profile_COMMON>")
    with open(out, "w") as f:
        f.write(text[:end] + COPPER + text[end:])


def pixel_errors(x, r, scale=None, halve=False):
    """Per-pixel relative squared difference of x and r, relative to `scale` (default r)."""
    n = len(r) // 3
    eps = compare_cycles.REL_MSE_EPS
    scale = r if scale is None else scale
    out = []
    for i in range(n):
        s = 0.0
        for c in range(3):
            a, b, d = x[3 * i + c], r[3 * i + c], scale[3 * i + c]
            s += (a - b) * (a - b) / (d * d + eps)
        out.append(s / (6.0 if halve else 3.0))
    return out


def tail(errors):
    total = sum(errors)
    worst = sorted(errors, reverse=True)
    n = len(errors)
    w1, w01 = sum(worst[:n // 100]), sum(worst[:n // 1000])
    return {"relmse": total / n, "without_worst_1pc": (total - w1) / n,
            "share_worst_1pc": w1 / total if total else 0.0,
            "share_worst_0_1pc": w01 / total if total else 0.0}


def main(argv):
    if len(argv) == 2 and argv[0] == "--copper-bunny":
        copper_bunny(argv[1])
        return 0
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        ref, w, h = compare_cycles.read_rgb(argv[0], tmp)

        def read(path):
            img, w2, h2 = compare_cycles.read_rgb(path, tmp)
            if (w2, h2) != (w, h):
                raise SystemExit(f"{path}: {w2}x{h2}, the reference is {w}x{h}")
            return img

        print("render  relMSE  without-worst-1%  share-worst-1%  share-worst-0.1%")
        pairs = argv[1] == "--pairs"
        for item in argv[2:] if pairs else argv[1:]:
            if pairs:
                a, b = item.split(",")
                t = tail(pixel_errors(read(a), read(b), ref, halve=True))
            else:
                t = tail(pixel_errors(read(item), ref))
            print(f"{item}  {t['relmse']:.4g}  {t['without_worst_1pc']:.4g}  "
                  f"{t['share_worst_1pc']:.3f}  {t['share_worst_0_1pc']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
