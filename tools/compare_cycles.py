#!/usr/bin/env python3
"""Equal-error time of candela's default render against Blender Cycles.

For each scene this renders (or takes from the cache):

  * a Cycles reference (fixed spp, default 4096) and a candela reference (uniform Sobol,
    `--adaptive none --sampler sobol`, default 2048 spp), both with a seed no measured render
    uses. Each renderer's error is measured against its OWN reference, because the two models
    differ in detail (Cycles tessellates spheres, its glass and microfacet models are its own);
    the relMSE between the two references is printed as a check that they agree;
  * Cycles at a fixed spp (default 64) and with Cycles' adaptive sampling (a small ladder of
    threshold:max-spp settings);
  * candela with its default settings over a ladder of `--noise-threshold` values (only the
    stopping point changes), extended until it brackets each Cycles error;
  * candela uniform at Cycles' fixed spp (`--adaptive none -s 64`): time per sample and error at
    equal spp, to tell what an equal-error time ratio is made of.

The candela time at a Cycles render's error is interpolated between the two bracketing ladder
points, linearly in log(time) against log(relMSE); the ratio printed is that time over the
Cycles render's time. Below 1, candela reaches the same error sooner.

Time: Cycles' `render_seconds` (its JSON line: the wall time of Blender's render operator, i.e.
scene synchronisation, BVH build and path tracing, without scene import and image writing)
against candela's build + render seconds (its `--progress json` done line: BVH build and path
tracing, without scene parsing and image writing). The bare path-tracing times (Cycles'
`cycles_pathtrace_seconds` stamp, candela's render seconds) are in the JSON output too.

relMSE = mean over pixels and RGB channels of (x - r)^2 / (r^2 + 0.01), the measure of
`candela converge`. Images are read by converting them to FITS (plain big-endian floats) with `oiiotool`.

Needs: python3 (standard library; numpy is used when present), blender (3.4, Debian package
`blender`), oiiotool (`openimageio-tools`) and a built candela.
"""

import argparse
import array
import hashlib
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# relMSE denominator offset: keeps black pixels from dominating (candela's kRelMseEps).
REL_MSE_EPS = 0.01
# Seed of both references: neither renderer's measured renders use it, so references and
# measured renders are independent.
REFERENCE_SEED = 7919
# Seed of candela's measured renders (Cycles' measured renders use Cycles' default, 0).
CANDELA_SEED = 1
CYCLES_SEED = 0
# Ladder extension: each new noise threshold is the last one times (or over) this factor.
LADDER_STEP = 1.4
# The ladder is extended at most this many times in each direction.
LADDER_MAX_EXTEND = 6
# 1-spp renders per renderer and scene whose least process CPU seconds is the start-up cost.
OVERHEAD_RUNS = 2
# Samples every pixel takes in the relative sampler's first batch (its least render).
FIRST_BATCH_SPP = 16
DEFAULT_SCENES = "CBspheres_lambertian,CBbunny,CBspheres"


def log(msg):
    print(f"[compare_cycles {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="tools/compare_cycles.py",
        description="Equal-error render time of candela's default settings against Blender "
        "Cycles (fixed spp and adaptive), each renderer measured against its own "
        "high-sample reference.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--candela", default=os.path.join(ROOT, "build", "candela"),
                   help="candela binary to measure")
    p.add_argument("--blender", default="blender", help="Blender executable (3.4)")
    p.add_argument("--cycles-script",
                   default=os.path.join(ROOT, "..", "shared", "tools", "cycles", "render_cycles.py"),
                   help="render_cycles.py (renders a CS184 scene with Cycles)")
    p.add_argument("--scenes-dir", default=os.path.join(ROOT, "..", "shared", "scenes", "cs184"),
                   help="directory of the scenes named by --scenes")
    p.add_argument("--scenes", default=DEFAULT_SCENES,
                   help="comma-separated scene names (without .dae) or .dae paths")
    p.add_argument("-r", "--resolution", nargs=2, type=int, default=[480, 360],
                   metavar=("W", "H"))
    p.add_argument("-m", "--max-depth", type=int, default=8,
                   help="candela -m and Cycles --max-bounces")
    p.add_argument("-t", "--threads", type=int, default=2, help="threads of every render")
    p.add_argument("--ref-spp", type=int, default=4096, help="samples of the Cycles reference")
    p.add_argument("--candela-ref-spp", type=int, default=2048,
                   help="samples of the candela reference (uniform Sobol; its own error, "
                   "printed, is a few percent of a 64-spp render's on the diffuse scenes)")
    p.add_argument("--cycles-spp", type=int, default=64, help="Cycles' fixed-spp render")
    p.add_argument("--cycles-adaptive", default="0.05:256,0.02:256,0.01:256",
                   help="Cycles adaptive renders, comma-separated THRESHOLD:MAX_SPP")
    p.add_argument("--ladder", default="0.07,0.05,0.035,0.025,0.02",
                   help="candela --noise-threshold values (default settings otherwise); "
                   "extended by factors of %.1f until every Cycles error is bracketed" % LADDER_STEP)
    p.add_argument("--cache", default=os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "candela", "cycles"),
        help="reference cache (keyed by scene content hash, resolution, depth, spp, mode)")
    p.add_argument("--refresh", action="store_true", help="re-render cached references")
    p.add_argument("--refs-only", action="store_true",
                   help="only make the references (and print their agreement)")
    p.add_argument("--repeat", type=int, default=1,
                   help="render each measured setting N times and keep the least time (the "
                   "image of a seed is the same every time); lessens a shared machine's noise")
    p.add_argument("--json", default=None, metavar="FILE", help="also write every figure here")
    p.add_argument("--keep", default=None, metavar="DIR",
                   help="keep the measured renders in DIR (default: a temporary directory)")
    a = p.parse_args(argv)
    if a.repeat < 1:
        p.error("--repeat must be >= 1")
    if a.threads < 1:
        p.error("--threads must be >= 1 (timings need a fixed thread count)")
    try:
        a.cycles_adaptive = [(float(x.split(":")[0]), int(x.split(":")[1]))
                             for x in a.cycles_adaptive.split(",") if x]
        a.ladder = sorted({float(x) for x in a.ladder.split(",") if x}, reverse=True)
    except (ValueError, IndexError):
        p.error("--cycles-adaptive takes THRESHOLD:MAX_SPP,...; --ladder numbers")
    if not a.ladder or min(a.ladder) <= 0:
        p.error("--ladder needs positive noise thresholds")
    return a


# --------------------------------------------------------------------------
# Images and errors
# --------------------------------------------------------------------------

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


def rel_mse(x, r):
    """mean (x - r)^2 / (r^2 + REL_MSE_EPS) over every pixel and channel."""
    if len(x) != len(r):
        raise RuntimeError("relMSE: images differ in size")
    try:
        import numpy as np
        a = np.frombuffer(x, dtype=np.float32).astype(np.float64)
        b = np.frombuffer(r, dtype=np.float32).astype(np.float64)
        return float(np.mean((a - b) ** 2 / (b * b + REL_MSE_EPS)))
    except ImportError:
        s = 0.0
        for a, b in zip(x, r):
            d = a - b
            s += d * d / (b * b + REL_MSE_EPS)
        return s / len(r)


# --------------------------------------------------------------------------
# Renders
# --------------------------------------------------------------------------

def rel_error_of_mean(var, r):
    """mean var / (r^2 + REL_MSE_EPS): the relMSE a render's own noise contributes, from the
    variance of each pixel's mean (an over-estimate for Sobol points, whose error falls faster
    than that of independent samples)."""
    return sum(v / (b * b + REL_MSE_EPS) for v, b in zip(var, r)) / len(r)


def scene_hash(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()[:12]


def ref_path(args, scene, spp, mode):
    stem = os.path.splitext(os.path.basename(scene))[0]
    w, h = args.resolution
    return os.path.join(args.cache, f"{stem}-{scene_hash(scene)}-{w}x{h}-m{args.max_depth}-"
                        f"{spp}spp-{mode}-seed{REFERENCE_SEED}.exr")


def render_cycles(args, scene, out, spp, seed, adaptive=None):
    """Renders with Cycles; returns its JSON line (dict)."""
    w, h = args.resolution
    cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "-P", args.cycles_script, "--", "--scene", scene, "--out", out,
           "--width", str(w), "--height", str(h), "--spp", str(spp),
           "--threads", str(args.threads), "--max-bounces", str(args.max_depth),
           "--light-mode", "candela", "--seed", str(seed)]
    if adaptive is not None:
        cmd += ["--adaptive", "--adaptive-threshold", str(adaptive)]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = next((l for l in p.stdout.splitlines() if l.startswith('{"tool": "cycles-peer"')), None)
    if p.returncode != 0 or line is None:
        raise RuntimeError(f"Cycles failed on {scene} (status {p.returncode}):\n"
                           + (p.stderr or p.stdout)[-2000:])
    return json.loads(line)


def render_candela(args, scene, out, extra, seed=CANDELA_SEED):
    """Renders with candela (-r, -m, -t fixed, plus `extra`); returns its JSON done line."""
    w, h = args.resolution
    cmd = [args.candela, "render", scene, "-r", str(w), str(h), "-m", str(args.max_depth),
           "-t", str(args.threads), "--seed", str(seed), "-f", out, "--progress", "json"] + extra
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    done = None
    for l in p.stdout.splitlines():
        if l.startswith("{") and '"event":"done"' in l:
            done = json.loads(l)
    if p.returncode != 0 or done is None:
        raise RuntimeError(f"candela failed on {scene} (status {p.returncode}): "
                           + " ".join(cmd) + "\n" + p.stderr[-2000:])
    done["command"] = cmd
    return done


def child_cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_of(render):
    """Process CPU seconds (all threads) of one render command."""
    c0 = child_cpu_seconds()
    render()
    return child_cpu_seconds() - c0


def repeated(args, render, seconds_of):
    """Runs `render` --repeat times; returns the run with the least seconds_of(run), with the
    whole command's CPU seconds (all threads; includes start-up) under "command_cpu_seconds"."""
    best = None
    for _ in range(args.repeat):
        c0 = child_cpu_seconds()
        info = render()
        info["command_cpu_seconds"] = child_cpu_seconds() - c0
        if best is None or seconds_of(info) < seconds_of(best):
            best = info
    return best


def cached(args, path, make):
    """Returns the JSON side file of the cached render at `path`, making it if absent."""
    side = path[:-4] + ".json"
    if not args.refresh and os.path.exists(path) and os.path.exists(side):
        with open(side) as f:
            return json.load(f)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path[:-4] + ".tmp.exr"
    log(f"rendering reference {os.path.basename(path)} (minutes)")
    info = make(tmp)
    with open(side + ".tmp", "w") as f:
        json.dump(info, f)
    os.replace(tmp, path)
    os.replace(side + ".tmp", side)
    return info


def references(args, scene):
    cy_path = ref_path(args, scene, args.ref_spp, "cycles-fixed")
    cy = cached(args, cy_path,
                lambda out: render_cycles(args, scene, out, args.ref_spp, REFERENCE_SEED))
    ca_path = ref_path(args, scene, args.candela_ref_spp, "candela-uniform-sobol")
    ca = cached(args, ca_path, lambda out: render_candela(
        args, scene, out,
        ["--adaptive", "none", "--sampler", "sobol", "-s", str(args.candela_ref_spp)],
        seed=REFERENCE_SEED))
    return cy_path, cy, ca_path, ca


# --------------------------------------------------------------------------
# Equal-error time
# --------------------------------------------------------------------------

def time_at_error(points, target):
    """candela seconds at relMSE `target`, from (seconds, relMSE) points: log-log interpolation
    between the bracketing pair. Above every point's error, the fastest point's time (candela's
    default cannot stop sooner than its first batch); below every point's error, extrapolation
    from the nearest point with relMSE proportional to 1/time. Returns (seconds, how)."""
    pts = sorted(points, key=lambda p: -p[1])  # error falling
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            f = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))), "interpolated"
    if target > pts[0][1]:
        return min(p[0] for p in pts), "fastest"
    t, e = pts[-1]
    return t * e / target, "extrapolated"


def candela_seconds(done):
    return done["time_s"]["build"] + done["time_s"]["render"]


def measure_scene(args, scene, tmpdir, outdir):
    stem = os.path.splitext(os.path.basename(scene))[0]
    cy_ref_path, cy_ref_info, ca_ref_path, ca_ref_info = references(args, scene)
    cy_ref, w, h = read_rgb(cy_ref_path, tmpdir)
    ca_ref, w2, h2 = read_rgb(ca_ref_path, tmpdir)
    if (w, h) != (w2, h2):
        raise RuntimeError(f"{stem}: the references differ in size")
    ca_var, _, _ = read_rgb(ca_ref_path, tmpdir, "variance.R,variance.G,variance.B")
    res = {"scene": stem, "file": scene, "refs_relmse": rel_mse(ca_ref, cy_ref),
           "candela_ref_own_relmse": rel_error_of_mean(ca_var, ca_ref),
           "cycles_ref": cy_ref_info, "candela_ref": ca_ref_info}
    log(f"{stem}: references agree to relMSE {res['refs_relmse']:.3g} (candela against Cycles); "
        f"the candela reference's own relMSE is at most {res['candela_ref_own_relmse']:.3g}")
    if args.refs_only:
        return res

    # Process CPU seconds of a 1-spp render: start-up, scene import, BVH build, image writing
    # (and one sample). Subtracted from each render's process CPU seconds, it leaves the CPU
    # seconds of sampling, which a shared machine's load changes far less than wall time.
    log(f"{stem}: 1-spp renders (start-up CPU seconds)")
    one = os.path.join(outdir, f"{stem}-one.exr")
    cy_over = min(cpu_of(lambda: render_cycles(args, scene, one, 1, CYCLES_SEED))
                  for _ in range(OVERHEAD_RUNS))
    ca_over = min(cpu_of(lambda: render_candela(args, scene, one, ["--adaptive", "none", "-s", "1"]))
                  for _ in range(OVERHEAD_RUNS))
    res.update({"cycles_overhead_cpu_seconds": cy_over, "candela_overhead_cpu_seconds": ca_over})

    # Cycles: fixed spp, then the adaptive settings.
    cycles = []
    settings = [("fixed", args.cycles_spp, None)] + [
        ("adaptive", spp, thr) for thr, spp in args.cycles_adaptive]
    for kind, spp, thr in settings:
        out = os.path.join(outdir, f"{stem}-cycles-{kind}-{spp}" + (f"-{thr}" if thr else "")
                           + ".exr")
        log(f"{stem}: Cycles {kind} {spp} spp" + (f", threshold {thr}" if thr else ""))
        info = repeated(args, lambda: render_cycles(args, scene, out, spp, CYCLES_SEED, thr),
                        lambda i: i["render_seconds"])
        img, _, _ = read_rgb(out, tmpdir)
        cycles.append({"kind": kind, "spp": spp, "threshold": thr,
                       "seconds": info["render_seconds"],
                       "pathtrace_seconds": info["cycles_pathtrace_seconds"],
                       "command_cpu_seconds": info["command_cpu_seconds"],
                       "cpu_seconds": info["command_cpu_seconds"] - cy_over,
                       "relmse": rel_mse(img, cy_ref)})

    # candela, default settings, over the noise-threshold ladder.
    ladder = []

    def run(thr):
        out = os.path.join(outdir, f"{stem}-candela-nt{thr:.5g}.exr")
        log(f"{stem}: candela default, --noise-threshold {thr:.5g}")
        done = repeated(args, lambda: render_candela(args, scene, out,
                                                     ["--noise-threshold", f"{thr:.6g}"]),
                        candela_seconds)
        img, _, _ = read_rgb(out, tmpdir)
        ladder.append({"noise_threshold": thr, "seconds": candela_seconds(done),
                       "render_seconds": done["time_s"]["render"],
                       "build_seconds": done["time_s"]["build"],
                       "command_cpu_seconds": done["command_cpu_seconds"],
                       "cpu_seconds": done["command_cpu_seconds"] - ca_over,
                       "spp_mean": done["spp_mean"], "relmse": rel_mse(img, ca_ref)})

    for thr in args.ladder:
        run(thr)
    targets = [c["relmse"] for c in cycles]
    for _ in range(LADDER_MAX_EXTEND):
        if min(p["relmse"] for p in ladder) <= min(targets):
            break
        run(min(p["noise_threshold"] for p in ladder) / LADDER_STEP)
    for _ in range(LADDER_MAX_EXTEND):
        top = max(ladder, key=lambda p: p["noise_threshold"])
        # At the first batch (every pixel's minimum) a higher threshold changes nothing.
        if max(p["relmse"] for p in ladder) >= max(targets) or top["spp_mean"] <= FIRST_BATCH_SPP:
            break
        run(top["noise_threshold"] * LADDER_STEP)
    ladder.sort(key=lambda p: -p["noise_threshold"])

    points = [(p["seconds"], p["relmse"]) for p in ladder]
    for c in cycles:
        t, how = time_at_error(points, c["relmse"])
        c["candela_seconds"] = t
        c["candela_estimate"] = how
        c["ratio"] = t / c["seconds"]
        t, _ = time_at_error([(p["render_seconds"], p["relmse"]) for p in ladder], c["relmse"])
        c["candela_pathtrace_seconds"] = t
        c["ratio_pathtrace"] = t / c["pathtrace_seconds"] if c["pathtrace_seconds"] else None
        t, _ = time_at_error([(p["cpu_seconds"], p["relmse"]) for p in ladder], c["relmse"])
        c["candela_cpu_seconds"] = t
        c["ratio_cpu"] = t / c["cpu_seconds"]

    # Diagnosis: candela uniform at Cycles' fixed spp (time per sample, error at equal spp).
    out = os.path.join(outdir, f"{stem}-candela-uniform-{args.cycles_spp}.exr")
    log(f"{stem}: candela uniform {args.cycles_spp} spp (diagnosis)")
    done = repeated(args, lambda: render_candela(
        args, scene, out, ["--adaptive", "none", "-s", str(args.cycles_spp)]), candela_seconds)
    img, _, _ = read_rgb(out, tmpdir)
    uni = {"spp": args.cycles_spp, "seconds": candela_seconds(done),
           "render_seconds": done["time_s"]["render"],
           "command_cpu_seconds": done["command_cpu_seconds"],
           "cpu_seconds": done["command_cpu_seconds"] - ca_over, "relmse": rel_mse(img, ca_ref)}
    fixed = cycles[0]
    uni["time_per_sample_ratio"] = uni["seconds"] / fixed["seconds"]
    uni["cpu_time_ratio"] = uni["cpu_seconds"] / fixed["cpu_seconds"]
    uni["pathtrace_time_ratio"] = (uni["render_seconds"] / fixed["pathtrace_seconds"]
                                   if fixed["pathtrace_seconds"] else None)
    uni["error_ratio_equal_spp"] = uni["relmse"] / fixed["relmse"]
    res.update({"cycles": cycles, "candela_ladder": ladder, "candela_uniform": uni})
    return res


# --------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------

def fmt(x, spec):
    return "-".rjust(int(spec.split(".")[0])) if x is None else format(x, spec)


def print_report(args, results):
    w, h = args.resolution
    print(f"candela {args.candela} against Cycles ({args.blender}), {w}x{h}, -m {args.max_depth}, "
          f"{args.threads} threads; references: Cycles {args.ref_spp} spp, candela "
          f"{args.candela_ref_spp} spp uniform Sobol; each renderer against its own")
    print("ratio = candela seconds at the Cycles render's relMSE / Cycles seconds. Wall: Cycles "
          "render_seconds (sync + BVH + path tracing)\nagainst candela build + render seconds; "
          "'PT ratio': path tracing alone (Cycles' render_time stamp, candela's render\nseconds); "
          "CPU: process CPU seconds less those of a 1-spp render of the same scene")
    print()
    print(f"{'':22} {'':>11} {'':>22} {'':>9} {'wall seconds':-^35} {'CPU seconds':-^27}")
    print(f"{'scene':22} {'refs relMSE':>11} {'Cycles render':>22} {'relMSE':>9} {'Cycles':>8} "
          f"{'candela':>8} {'ratio':>7} {'PT ratio':>8} {'Cycles':>8} {'candela':>8} {'ratio':>9}")
    for r in results:
        first = True
        for c in r.get("cycles", [{}] if args.refs_only else []):
            if not c:
                print(f"{r['scene']:22} {r['refs_relmse']:11.3g}")
                continue
            label = (f"fixed {c['spp']} spp" if c["kind"] == "fixed"
                     else f"adaptive {c['threshold']:g}/{c['spp']}")
            est = {"interpolated": "", "fastest": " (candela's least render)",
                   "extrapolated": " (extrapolated)"}[c["candela_estimate"]]
            print(f"{r['scene'] if first else '':22} "
                  f"{format(r['refs_relmse'], '11.3g') if first else '':>11} {label:>22} "
                  f"{c['relmse']:9.3g} {c['seconds']:8.2f} {c['candela_seconds']:8.2f} "
                  f"{c['ratio']:7.3f} {fmt(c['ratio_pathtrace'], '8.3f')} "
                  f"{c['cpu_seconds']:8.2f} {c['candela_cpu_seconds']:8.2f} "
                  f"{c['ratio_cpu']:9.3f}{est}")
            first = False
    if args.refs_only:
        return
    print()
    print("candela reference's own relMSE (upper bound, from its variance channel): " + ", ".join(
        f"{r['scene']} {r['candela_ref_own_relmse']:.3g}" for r in results))
    print()
    print("candela ladder (default settings, --noise-threshold varied):")
    print(f"{'scene':22} {'threshold':>9} {'mean spp':>9} {'wall s':>8} {'CPU s':>8} {'relMSE':>9}")
    for r in results:
        for i, p in enumerate(r["candela_ladder"]):
            print(f"{r['scene'] if i == 0 else '':22} {p['noise_threshold']:9.4g} "
                  f"{p['spp_mean']:9.1f} {p['seconds']:8.2f} {p['cpu_seconds']:8.2f} "
                  f"{p['relmse']:9.3g}")
    print()
    print(f"diagnosis at {args.cycles_spp} spp (candela --adaptive none -s {args.cycles_spp} "
          "against Cycles fixed):")
    print(f"{'scene':22} {'candela s':>9} {'Cycles s':>9} {'time ratio':>10} {'PT ratio':>8} "
          f"{'CPU ratio':>9} {'candela relMSE':>14} {'Cycles relMSE':>13} {'error ratio':>11}")
    for r in results:
        u, c = r["candela_uniform"], r["cycles"][0]
        print(f"{r['scene']:22} {u['seconds']:9.2f} {c['seconds']:9.2f} "
              f"{u['time_per_sample_ratio']:10.3f} {fmt(u['pathtrace_time_ratio'], '8.3f')} "
              f"{u['cpu_time_ratio']:9.3f} "
              f"{u['relmse']:14.3g} {c['relmse']:13.3g} {u['error_ratio_equal_spp']:11.3f}")


def main(argv):
    args = parse_args(argv)
    for tool in (args.blender, "oiiotool"):
        if shutil.which(tool) is None:
            sys.exit(f"compare_cycles: {tool} not found (apt-get install blender openimageio-tools)")
    if not os.access(args.candela, os.X_OK):
        sys.exit(f"compare_cycles: no candela binary at {args.candela} (--candela PATH)")
    if not os.path.exists(args.cycles_script):
        sys.exit(f"compare_cycles: no render_cycles.py at {args.cycles_script} (--cycles-script)")
    scenes = []
    for s in args.scenes.split(","):
        path = s if s.endswith(".dae") else os.path.join(args.scenes_dir, s + ".dae")
        if not os.path.exists(path):
            sys.exit(f"compare_cycles: no scene {path}")
        scenes.append(os.path.normpath(path))

    load_start = os.getloadavg()
    results = []
    with tempfile.TemporaryDirectory(prefix="compare_cycles.") as tmpdir:
        outdir = args.keep or tmpdir
        os.makedirs(outdir, exist_ok=True)
        for scene in scenes:
            results.append(measure_scene(args, scene, tmpdir, outdir))
    load_end = os.getloadavg()
    print_report(args, results)
    print()
    print("load average (1, 5, 15 min): at start %.2f %.2f %.2f, at end %.2f %.2f %.2f"
          % (load_start + load_end))
    if args.json:
        meta = {"candela": args.candela, "resolution": args.resolution,
                "max_depth": args.max_depth, "threads": args.threads, "ref_spp": args.ref_spp,
                "candela_ref_spp": args.candela_ref_spp,
                "load_average_start": load_start,
                "load_average_end": load_end, "time": time.strftime("%Y-%m-%dT%H:%M:%SZ",
                                                                       time.gmtime())}
        with open(args.json, "w") as f:
            json.dump({"settings": meta, "scenes": results}, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
