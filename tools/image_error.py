#!/usr/bin/env python3
"""Image error as candela measures it: the one home of it for the tools
(tools/compare_cycles.py, tools/tail_error.py).

    MSE    = mean over pixels and RGB channels of (x - r)^2
    relMSE = mean over pixels and RGB channels of (x - r)^2 / (r^2 + REL_MSE_EPS)

the measures of include/candela/diagnostics/converge.h (`candela converge`, `candela compare`),
REL_MSE_EPS being its kRelMseEps. Images are read through oiiotool (read_rgb).

`candela compare IMAGE REFERENCE` prints the same whole-image MSE and relMSE (candela_compare
runs it), to four significant digits, and no per-pixel errors. The tools here need the per-pixel
errors (the share of the worst pixels) and interpolate relMSE to more digits, so they compute
it with this module; the self-test checks the two agree.

    python3 tools/image_error.py --self-test [--candela BUILD/candela]

checks the measures, that REL_MSE_EPS is converge.h's kRelMseEps, and, given a candela binary
and oiiotool, that this module and `candela compare` give one relMSE for two small renders.
"""

import array
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# relMSE's denominator offset: keeps black pixels from dominating. candela's kRelMseEps
# (include/candela/diagnostics/converge.h); the self-test reads it there.
REL_MSE_EPS = 0.01
# The tail whose share of the squared error the tools report: the worst 1 % of pixels.
TAIL_FRACTION = 0.01


def read_rgb(path, tmpdir, channels="R,G,B"):
    """RGB floats of an EXR (interleaved, in the row order oiiotool writes FITS), with width
    and height. oiiotool converts to FITS: 32-bit floats, big-endian, after a header of 80-byte
    cards in 2880-byte blocks."""
    fits = os.path.join(tmpdir, "read.fits")
    subprocess.run(["oiiotool", path, "--ch", channels, "--eraseattrib", ".*", "-d", "float",
                    "-o", fits], check=True, stdout=subprocess.DEVNULL)
    with open(fits, "rb") as f:
        data = f.read()
    os.remove(fits)
    cards, pos = {}, 0
    while True:
        card = data[pos:pos + 80].decode("ascii", "replace")
        pos += 80
        if card.rstrip() == "END":
            break
        if pos >= len(data):
            raise RuntimeError(f"{path}: oiiotool wrote a FITS header without END")
        if card[8:10] == "= ":
            cards[card[:8].strip()] = card[10:].split("/")[0].strip()
    pos = (pos + 2879) // 2880 * 2880
    if (cards.get("BITPIX"), cards.get("NAXIS"), cards.get("NAXIS1")) != ("-32", "3", "3"):
        raise RuntimeError(f"{path}: unexpected FITS layout {cards}")
    w, h = int(cards["NAXIS2"]), int(cards["NAXIS3"])
    px = array.array("f")
    px.frombytes(data[pos:pos + 12 * w * h])
    if len(px) != 3 * w * h:
        raise RuntimeError(f"{path}: FITS data is short")
    if sys.byteorder == "little":
        px.byteswap()
    return px, w, h


def _numpy():
    try:
        import numpy
        return numpy
    except ImportError:
        return None


def pixel_errors(x, r, scale=None, np=_numpy()):
    """Per pixel, the sum over its RGB channels of (x - r)^2 / (s^2 + REL_MSE_EPS), s the
    pixel's value in `scale` (default r). Uses numpy when it is there (np=None: without)."""
    scale = r if scale is None else scale
    if len(x) != len(r) or len(scale) != len(r) or len(r) % 3:
        raise RuntimeError("relMSE: images differ in size")
    if np is not None:
        a, b, s = (np.asarray(v, dtype=np.float64) for v in (x, r, scale))
        return ((a - b) ** 2 / (s * s + REL_MSE_EPS)).reshape(-1, 3).sum(axis=1).tolist()
    out = []
    for i in range(0, len(r), 3):
        e = 0.0
        for a, b, s in zip(x[i:i + 3], r[i:i + 3], scale[i:i + 3]):
            e += (a - b) * (a - b) / (s * s + REL_MSE_EPS)
        out.append(e)
    return out


def rel_mse(x, r):
    """relMSE of image x against reference r (flat RGB sequences of one size)."""
    e = pixel_errors(x, r)
    return sum(e) / (3 * len(e))


def mse(x, r):
    """MSE of image x against reference r, in radiance^2."""
    if len(x) != len(r) or len(r) % 3:
        raise RuntimeError("MSE: images differ in size")
    return sum((a - b) * (a - b) for a, b in zip(x, r)) / len(r)


def rel_error_of_mean(var, r):
    """mean var / (r^2 + REL_MSE_EPS): the relMSE a render's own noise contributes, from the
    variance of each pixel's mean (an over-estimate for Sobol points, whose error falls faster
    than that of independent samples)."""
    return sum(v / (b * b + REL_MSE_EPS) for v, b in zip(var, r)) / len(r)


def image_mean(px):
    """The mean of every pixel channel of an image."""
    return sum(px) / len(px)


def std_err_of_mean(var):
    """The standard error of image_mean() from the variance of each pixel's mean (interleaved
    RGB, candela's variance channel). A pixel's channels come from the same paths, so their
    standard deviations add (fully correlated: an upper bound); pixels are independent."""
    if len(var) % 3:
        raise RuntimeError("std_err_of_mean: not RGB")
    total = 0.0
    for i in range(0, len(var), 3):
        sd = sum(max(v, 0.0) ** 0.5 for v in var[i:i + 3])
        total += sd * sd
    return total ** 0.5 / len(var)


def tail_share(errors, fraction=TAIL_FRACTION):
    """Share of the summed per-pixel error that the worst `fraction` of pixels carry (at least
    one pixel). 0 for an image without error."""
    total = sum(errors)
    if total <= 0:
        return 0.0
    n = max(1, int(round(fraction * len(errors))))
    return sum(sorted(errors, reverse=True)[:n]) / total


def candela_compare(candela, image, reference):
    """(MSE, relMSE) of `image` against `reference` as `candela compare` prints them (four
    significant digits)."""
    p = subprocess.run([candela, "compare", image, reference], capture_output=True, text=True)
    m = re.search(r"^whole image\s+MSE (\S+)\s+relMSE (\S+)", p.stdout, re.M)
    if p.returncode != 0 or m is None:
        raise RuntimeError(f"candela compare {image} {reference} failed (status "
                           f"{p.returncode}): {p.stderr.strip()[-500:]}")
    return float(m.group(1)), float(m.group(2))


# ---- self-test --------------------------------------------------------------------------------

def converge_h_eps():
    """kRelMseEps as include/candela/diagnostics/converge.h defines it."""
    with open(os.path.join(ROOT, "include", "candela", "diagnostics", "converge.h")) as f:
        m = re.search(r"constexpr double kRelMseEps = ([0-9.eE+-]+);", f.read())
    if m is None:
        raise AssertionError("converge.h no longer defines kRelMseEps as a double literal")
    return float(m.group(1))


def agrees_with_candela(candela, tmpdir):
    """Renders a small scene with two seeds and checks that relMSE and MSE of one against the
    other are `candela compare`'s (to the four digits it prints)."""
    renders = []
    for seed in (1, 2):
        out = os.path.join(tmpdir, f"seed{seed}.exr")
        subprocess.run([candela, "render", os.path.join(ROOT, "scenes", "cornell-box.dae"),
                        "-r", "24", "18", "-s", "4", "--adaptive", "none", "--seed", str(seed),
                        "-t", "1", "-q", "-f", out], check=True, stdout=subprocess.DEVNULL)
        renders.append(out)
    a, _, _ = read_rgb(renders[0], tmpdir)
    b, _, _ = read_rgb(renders[1], tmpdir)
    their_mse, their_rel = candela_compare(candela, renders[0], renders[1])
    # `candela compare` prints four significant digits: half a unit of the fourth.
    printed = 5e-4
    assert their_rel > 0 and abs(rel_mse(a, b) - their_rel) <= printed * their_rel, (
        rel_mse(a, b), their_rel)
    assert abs(mse(a, b) - their_mse) <= printed * their_mse, (mse(a, b), their_mse)


def self_test(candela=None):
    import shutil
    import tempfile

    def close(a, b, tol=1e-9):
        return abs(a - b) <= tol * max(1.0, abs(a), abs(b))

    # The mean and its standard error: two pixels, one fully correlated in its channels.
    assert close(image_mean([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), 3.5)
    assert close(std_err_of_mean([1.0, 1.0, 1.0, 0.0, 0.0, 4.0]), (9.0 + 4.0) ** 0.5 / 6)

    assert REL_MSE_EPS == converge_h_eps(), (REL_MSE_EPS, converge_h_eps())
    # Two pixels, one off by 1 in every channel of r = 1; with and without numpy.
    r = array.array("f", [1, 1, 1, 0, 0, 0])
    x = array.array("f", [2, 2, 2, 0, 0, 0])
    for np in {_numpy(), None}:
        e = pixel_errors(x, r, np=np)
        assert close(e[0], 3 / 1.01) and e[1] == 0, e
        # Against a scale of 2: the pair's difference relative to another image.
        e = pixel_errors(x, r, array.array("f", [2, 2, 2, 1, 1, 1]), np=np)
        assert close(e[0], 3 / 4.01) and e[1] == 0, e
    assert close(rel_mse(x, r), 3 / 1.01 / 6) and close(mse(x, r), 0.5)
    try:
        rel_mse(x, r[:3])
        raise AssertionError("images of different sizes must be refused")
    except RuntimeError:
        pass
    assert close(rel_error_of_mean([0.01, 0.0], [1.0, 0.0]), 0.01 / 1.01 / 2)
    # Tail share: one pixel of 100 carrying 10 of a total of 109.
    assert close(tail_share([1.0] * 99 + [10.0]), 10 / 109)
    assert close(tail_share([0.5] * 200), 0.01)  # 2 of 200 equal pixels
    assert close(tail_share([1.0] * 10 + [2.0], 0.001), 2 / 12)  # at least one pixel
    assert tail_share([0.0] * 10) == 0.0
    with_candela = candela is not None and shutil.which("oiiotool") is not None
    if with_candela:
        with tempfile.TemporaryDirectory() as tmp:
            agrees_with_candela(candela, tmp)
    print("image_error self-test: ok" + (" (and candela compare agrees)" if with_candela else
                                         " (not against candela compare: no binary or oiiotool)"))
    return 0


if __name__ == "__main__":
    argv = sys.argv[1:]
    if argv[:1] == ["--self-test"] and len(argv) in (1, 3) and argv[1:2] in ([], ["--candela"]):
        sys.exit(self_test(argv[2] if len(argv) == 3 else None))
    print(__doc__.strip(), file=sys.stderr)
    sys.exit(2)
