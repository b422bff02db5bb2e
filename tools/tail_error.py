#!/usr/bin/env python3
"""Where the squared error of a render sits: its relMSE against a reference, the relMSE left
when the worst 1 % of pixels are set aside, and the share of the squared error those pixels
(and the worst 0.1 %) carry. Fireflies (single samples of large weight) put most of the error
in a few pixels; noise spread evenly does not.

    tools/tail_error.py REFERENCE.exr RENDER.exr [RENDER.exr ...]
    tools/tail_error.py REFERENCE.exr --pairs A.exr,B.exr [C.exr,D.exr ...]
    tools/tail_error.py --copper-bunny OUT.dae
    tools/tail_error.py --self-test

A pixel's error is the mean over RGB of (x - r)^2 / (r^2 + 0.01), candela's relMSE measure
(tools/image_error.py, which reads the images through oiiotool). The worst 1 % (0.1 %) are the
round(n / 100) (round(n / 1000), at least one) pixels of largest error, as in
tools/compare_cycles.py.

--pairs measures noise alone, without the reference's own noise or any difference of models
between renderers: for two renders of one renderer with independent seeds, half of the mean of
(a - b)^2 / (r^2 + 0.01) is the relMSE of one of them against its own converged mean (the
reference only scales the pixels). The shares are those of the pixels of (a - b)^2.

--copper-bunny writes the performance suite's copper bunny (tools/scene_writer.py: the course's
CBbunny.dae with the bunny in the CS184 copper microfacet conductor, alpha 0.05, the eta and k of
CBbunny_microfacet_cu.dae), for the per-sample error figures of docs/performance.md. Write it
outside the repository: the course scenes are not copied into it.
"""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import image_error  # noqa: E402  (the image reader and the error measures)
import scene_writer  # noqa: E402  (the copper bunny)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CBBUNNY = os.path.join(ROOT, "..", "shared", "scenes", "cs184", "CBbunny.dae")
# The far tail reported beside image_error's worst 1 %: the worst 0.1 % of pixels.
FAR_TAIL_FRACTION = 0.001


def write_copper_bunny(out):
    with open(CBBUNNY) as f:
        text = scene_writer.copper_bunny(f.read())
    with open(out, "w") as f:
        f.write(text)


def tail(x, r, scale=None, halve=False):
    """relMSE of x against r (relative to `scale`, default r; halved for a pair of renders),
    that left without the worst 1 % of pixels, and the shares of the worst 1 % and 0.1 %."""
    errors = image_error.pixel_errors(x, r, scale)
    total, n = sum(errors), len(errors)
    relmse = total / ((6 if halve else 3) * n)
    w1 = image_error.tail_share(errors, image_error.TAIL_FRACTION)
    return {"relmse": relmse, "without_worst_1pc": relmse * (1 - w1), "share_worst_1pc": w1,
            "share_worst_0_1pc": image_error.tail_share(errors, FAR_TAIL_FRACTION)}


def self_test():
    # 1000 pixels of value 1: 990 off by 0.1, 9 by 1 and one by 3 in every channel.
    r = [1.0] * 3000
    x = [1.1] * 2970 + [2.0] * 27 + [4.0] * 3
    errs = [0.01] * 990 + [1.0] * 9 + [9.0] * 1
    total = sum(errs) / 1.01
    t = tail(x, r)
    assert abs(t["relmse"] - total / 1000) < 1e-12, t
    assert abs(t["share_worst_1pc"] - 18 / 27.9) < 1e-9, t
    assert abs(t["share_worst_0_1pc"] - 9 / 27.9) < 1e-9, t
    assert abs(t["without_worst_1pc"] - 9.9 / 1.01 / 1000) < 1e-12, t
    # A pair of renders: half the relMSE of their difference, relative to the reference.
    p = tail(x, r, [2.0] * 3000, halve=True)
    assert abs(p["relmse"] - sum(e * 1.01 / 4.01 for e in errs) / 1.01 / 2000) < 1e-12, p
    print("tail_error self-test: ok")
    return 0


def main(argv):
    if argv == ["--self-test"]:
        return self_test()
    if len(argv) == 2 and argv[0] == "--copper-bunny":
        write_copper_bunny(argv[1])
        return 0
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        ref, w, h = image_error.read_rgb(argv[0], tmp)

        def read(path):
            img, w2, h2 = image_error.read_rgb(path, tmp)
            if (w2, h2) != (w, h):
                raise SystemExit(f"{path}: {w2}x{h2}, the reference is {w}x{h}")
            return img

        print("render  relMSE  without-worst-1%  share-worst-1%  share-worst-0.1%")
        pairs = argv[1] == "--pairs"
        for item in argv[2:] if pairs else argv[1:]:
            if pairs:
                a, b = item.split(",")
                t = tail(read(a), read(b), ref, halve=True)
            else:
                t = tail(read(item), ref)
            print(f"{item}  {t['relmse']:.4g}  {t['without_worst_1pc']:.4g}  "
                  f"{t['share_worst_1pc']:.3f}  {t['share_worst_0_1pc']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
