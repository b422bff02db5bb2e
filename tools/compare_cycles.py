#!/usr/bin/env python3
"""The performance suite: candela against Blender Cycles on one scene of every kind.

The suite (`tools/suite_scenes.py`, `--list`): diffuse Cornell boxes, mirror and glass spheres,
rough-metal spheres, a rough-copper bunny, a mirror coil, a large mesh, an open scene under
ambient, directional and environment light, and many lights. `--scenes` picks some (suite
names or .dae paths). For each scene this renders (or takes from the cache):

  * a Cycles reference (fixed spp, default 2048) and a candela reference (uniform Sobol,
    `--adaptive none --sampler sobol`, default 2048 spp), both with a seed no measured render
    uses, cached by the scene's content (and its environment map's pixels), resolution,
    depth, spp and mode. A cached reference with more samples than asked for is used instead;
  * Cycles at a fixed spp (default 64), and optionally with Cycles' adaptive sampling;
  * candela at the same fixed spp with `--adaptive none` (per-sample error, uniform ray rate)
    and with its default sampler spending the same budget (`-s 64 --noise-threshold 0`: the
    default sampler's ray rate, and its error at that budget);
  * candela with its default settings over a ladder of `--noise-threshold` values, extended
    until it brackets each Cycles error, and refined between two bracketing points whose
    relMSE differ by more than a factor of 2 (log-log interpolation over a wider gap misjudges
    the curve the default sampler's first batches bend).

Per-sample error: relMSE at the fixed spp of each renderer against Cycles' reference and
against candela's reference (the two should agree), and the share of the squared error that the
worst 1 % of pixels carry; with `--error-seeds N`, the means over N seeds of each renderer
(the first seed's render is the timed one, the others are rendered for their error alone).
Equal-error time: candela's time at a Cycles render's error (with several seeds, the mean of
Cycles' fixed renders'; each renderer against its own reference: their models differ in
detail) is interpolated between the two bracketing ladder points, linearly in log(time)
against log(relMSE), and
divided by the Cycles render's time, `render_seconds` (Blender's render operator: sync, BVH
build and path tracing; not import or image writing). candela's time is taken two ways:
whole process (the `candela render` command's wall time, what a user waits for: start-up,
load, build, render, write) and build + render (its `--progress json` done line). Below 1,
candela reaches the error sooner.

relMSE = mean over pixels and RGB channels of (x - r)^2 / (r^2 + 0.01), the measure of
`candela converge` and `candela compare`, computed by tools/image_error.py (which reads the images
by converting them to FITS with `oiiotool`).

Cycles renders through the peer script render_cycles.py, run by `tools/cycles_world.py`, which
adds the scene's ambient lights and the environment map to Cycles' world (the peer script
leaves the world black). What the peer script cannot render (it warns: spot lights, textures,
...) is listed under each scene, and a scene with such a note is marked in the tables.

Results are written to --json after every scene; `--resume` skips the scenes whose results it
already holds for the same settings, candela binary and scene files.

Needs: python3 (standard library; numpy is used when present), blender (3.4, Debian package
`blender`), oiiotool (`openimageio-tools`) and a built candela. `--self-test` checks the pure
logic without any of them.
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import suite_scenes  # noqa: E402  (the suite's scenes, beside this file)
from image_error import (REL_MSE_EPS, pixel_errors, read_rgb,  # noqa: E402
                         rel_error_of_mean, rel_mse, tail_share, image_mean,
                         std_err_of_mean)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

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
# Log-log interpolation assumes relMSE is a power of time between the two bracketing points;
# the default sampler's first batches bend that curve, so a bracket whose relMSE falls by more
# than this factor gets a point at the geometric mean of its two thresholds, ...
LADDER_MAX_GAP = 2.0
# ... at most this many times per target.
LADDER_MAX_BISECT = 3
# 1-spp renders per renderer and scene whose least process CPU seconds is the start-up cost.
OVERHEAD_RUNS = 2
# Samples every pixel takes in the relative sampler's first batch (its least render).
FIRST_BATCH_SPP = 16
# The references "disagree" (the renderers render different things: a model difference or a
# part one of them leaves out) when their relMSE against each other exceeds this many times what
# their own noise explains. Noise alone gives a ratio near 1; the factor leaves room for the
# rough estimate of the Cycles reference's own error (its 64-spp render's error scaled by spp).
REFS_DISAGREE_FACTOR = 3.0
# Bump when the measurement changes, so that --resume does not mix old and new results.
RESULTS_VERSION = 7
# Bump when the Cycles side's reading of a scene changes (tools/cycles_world.py, the peer
# script's options in render_cycles), so that no cached Cycles reference of an older reading is
# taken for a new one. 2: the file's normals, two-sided emissive meshes, short matrices padded.
# 3: Cycles' bounce limit one below candela's -m (cycles_max_bounces). 4: point lights in a
# face's plane split in two half-space lamps, emissive meshes linked smallest triangles first.
CYCLES_READING_VERSION = 4


def cycles_max_bounces(max_depth):
    """Cycles' max_bounces for candela's -m. candela's -m counts scattering events, the one whose
    light next-event estimation finds included (spec 5.1: -m 1 is direct light); Cycles'
    max_bounces counts the bounces after that one (0 is direct light). candela has emitters seen
    directly only at -m 0, which no Cycles setting gives."""
    if max_depth < 1:
        raise ValueError("-m 0 (emitters seen directly only) has no Cycles equivalent")
    return max_depth - 1


def log(msg):
    print(f"[compare_cycles {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="tools/compare_cycles.py",
        description="The performance suite: per-sample error, ray rates and equal-error render "
        "time of candela against Blender Cycles on one scene of every kind.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--candela", default=os.path.join(ROOT, "build", "candela"),
                   help="candela binary to measure")
    p.add_argument("--blender", default="blender", help="Blender executable (3.4)")
    p.add_argument("--cycles-script",
                   default=os.path.join(ROOT, "..", "shared", "tools", "cycles", "render_cycles.py"),
                   help="render_cycles.py (renders a CS184 scene with Cycles)")
    p.add_argument("--scenes-dir", default=os.path.join(ROOT, "..", "shared", "scenes", "cs184"),
                   help="directory of the course scenes")
    p.add_argument("--scene-dir", action="append", default=[], metavar="DIR",
                   help="also search DIR for candela's own suite scenes, before the "
                   "repository's scenes/ (repeatable; the first that has the file wins)")
    p.add_argument("--scenes", default="suite",
                   help="comma-separated suite scene names or .dae paths; 'suite' = the whole "
                   "suite (--list)")
    p.add_argument("--list", action="store_true", help="list the suite and exit")
    p.add_argument("-r", "--resolution", nargs=2, type=int, default=[480, 360],
                   metavar=("W", "H"))
    p.add_argument("-m", "--max-depth", type=int, default=8,
                   help="candela -m; Cycles renders the same paths with --max-bounces one "
                   "lower (it does not count the scattering event whose light is sampled)")
    p.add_argument("-t", "--threads", type=int, default=2, help="threads of every render")
    p.add_argument("--ref-spp", type=int, default=2048,
                   help="samples of the Cycles reference (a cached one with more is used "
                   "instead; 4096 halves the reference's own error)")
    p.add_argument("--candela-ref-spp", type=int, default=2048,
                   help="samples of the candela reference (uniform Sobol; its own error, "
                   "printed, is a few percent of a 64-spp render's on the diffuse scenes)")
    p.add_argument("--cycles-spp", type=int, default=64,
                   help="the fixed spp of the per-sample comparison and of Cycles' render")
    p.add_argument("--cycles-adaptive", default="",
                   help="also Cycles adaptive renders, comma-separated THRESHOLD:MAX_SPP "
                   "(e.g. 0.05:256,0.02:256,0.01:256)")
    p.add_argument("--ladder", default="0.05,0.035,0.025",
                   help="candela --noise-threshold values (default settings otherwise), "
                   "rendered from the highest down until one reaches every Cycles error, then "
                   "extended by factors of %.1f until every Cycles error is bracketed" % LADDER_STEP)
    p.add_argument("--cache", default=os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "candela", "cycles"),
        help="reference cache (keyed by scene content hash, resolution, depth, spp, mode); "
        "derived suite scenes are written to its derived/ folder")
    p.add_argument("--refresh", action="store_true", help="re-render cached references")
    p.add_argument("--refresh-candela", action="store_true",
                   help="re-render candela's cached references only (after a change to its images)")
    p.add_argument("--refs-only", action="store_true",
                   help="only make the references (and print their agreement)")
    p.add_argument("--repeat", type=int, default=1,
                   help="render each measured setting N times, in N rounds over all of a "
                   "scene's timed renders (Cycles' and candela's alternate), and keep each "
                   "setting's least time (the image of a seed is the same every time); lessens "
                   "a shared machine's noise")
    p.add_argument("--error-seeds", type=int, default=1, metavar="N",
                   help="render the fixed-spp comparison (Cycles' fixed render and candela's "
                   "uniform one) with N seeds each and report the means of their errors and "
                   "worst-1 %% shares (the first seed's render is the timed one); one render's "
                   "error on a scene whose error sits in a few pixels (fireflies, a pixel edge) "
                   "moves by tens of per cent from seed to seed")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="write every figure here (after each scene)")
    p.add_argument("--resume", action="store_true",
                   help="keep the results --json FILE already holds for the same settings, "
                   "binary and scene files, measure only the rest, and keep the file's results "
                   "of scenes this run does not name (the file accumulates)")
    p.add_argument("--markdown", action="store_true",
                   help="also print the suite table in the markdown of docs/performance.md")
    p.add_argument("--keep", default=None, metavar="DIR",
                   help="keep the measured renders in DIR (default: a temporary directory)")
    p.add_argument("--self-test", action="store_true",
                   help="check the pure logic (no renderer needed) and exit")
    a = p.parse_args(argv)
    if a.self_test or a.list:
        return a
    if a.repeat < 1:
        p.error("--repeat must be >= 1")
    if a.error_seeds < 1:
        p.error("--error-seeds must be >= 1")
    if a.threads < 1:
        p.error("--threads must be >= 1 (timings need a fixed thread count)")
    if a.max_depth < 1:
        p.error("-m must be >= 1 (-m 0, emitters seen directly only, has no Cycles equivalent)")
    if a.resume and not a.json:
        p.error("--resume needs --json FILE (the results to resume)")
    try:
        a.cycles_adaptive = [(float(x.split(":")[0]), int(x.split(":")[1]))
                             for x in a.cycles_adaptive.split(",") if x]
        a.ladder = sorted({float(x) for x in a.ladder.split(",") if x}, reverse=True)
    except (ValueError, IndexError):
        p.error("--cycles-adaptive takes THRESHOLD:MAX_SPP,...; --ladder numbers")
    if not a.ladder or min(a.ladder) <= 0:
        p.error("--ladder needs positive noise thresholds")
    a.scene_dir = a.scene_dir + [os.path.join(ROOT, "scenes")]
    return a


# --------------------------------------------------------------------------
# Images and errors
# --------------------------------------------------------------------------

def error_figures(img, cy_ref, ca_ref):
    """relMSE of an image against both references and its worst-1 % share (against Cycles')."""
    e = pixel_errors(img, cy_ref)
    return {"relmse": sum(e) / (3 * len(e)), "relmse_vs_candela_ref": rel_mse(img, ca_ref),
            "tail_share": tail_share(e)}


def mean_figures(figures):
    """error_figures() of renders of one setting with different seeds: the mean of each figure,
    and the per-seed relMSE (against Cycles' reference) as "relmse_seeds"."""
    out = {k: sum(f[k] for f in figures) / len(figures) for k in figures[0]}
    out["relmse_seeds"] = [f["relmse"] for f in figures]
    return out


def seed_figures(args, first, render, tmpdir, cy_ref, ca_ref):
    """The error figures of the fixed-spp comparison over --error-seeds seeds: `first` are the
    timed render's (seed 0 of the setting); render(k) renders seed k and returns its image's
    path."""
    figures = [first]
    for k in range(1, args.error_seeds):
        img, _, _ = read_rgb(render(k), tmpdir)
        figures.append(error_figures(img, cy_ref, ca_ref))
    return mean_figures(figures)


# --------------------------------------------------------------------------
# Scenes, keys and the cache
# --------------------------------------------------------------------------

class Scene:
    """A scene to measure: its name, kind, file, environment map (or None), whether it is seen
    from the file's camera pose, and its cache key."""

    def __init__(self, name, kind, path, env, key, file_camera=False):
        self.name, self.kind, self.path, self.env, self.key = name, kind, path, env, key
        self.file_camera = file_camera


def file_hash(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def scene_key(path, env_pixels=None, file_camera=False):
    """12 hex digits of the scene file's SHA-256, with the environment map's pixels (not its
    file: its header carries a date) when there is one, and the camera mode when it is not the
    framed camera."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        h.update(f.read())
    if env_pixels is not None:
        h.update(b"env")
        h.update(env_pixels)
    if file_camera:
        h.update(b"camera=file")
    return h.hexdigest()[:12]


def ref_stem(args, scene, mode):
    w, h = args.resolution
    return f"{scene.name}-{scene.key}-{w}x{h}-m{args.max_depth}-%dspp-{mode}-seed{REFERENCE_SEED}"


def find_reference(args, scene, spp, mode, refresh=False):
    """Path of the reference to use: a cached one of at least `spp` samples (the most samples
    first), else (or with `refresh` or --refresh) the path at which to render one of `spp`."""
    stem = ref_stem(args, scene, mode)
    if not (args.refresh or refresh) and os.path.isdir(args.cache):
        have = []
        head, tail = stem.split("%d")
        for f in os.listdir(args.cache):
            if f.startswith(head) and f.endswith(tail + ".exr"):
                n = f[len(head):-len(tail + ".exr")]
                if n.isdigit() and int(n) >= spp and os.path.exists(
                        os.path.join(args.cache, f[:-4] + ".json")):
                    have.append(int(n))
        if have:
            return os.path.join(args.cache, stem % max(have) + ".exr")
    return os.path.join(args.cache, stem % spp + ".exr")


def cached(args, path, make, refresh=False):
    """Returns the JSON side file of the cached render at `path`, making it if absent (or with
    `refresh` or --refresh)."""
    side = path[:-4] + ".json"
    if not (args.refresh or refresh) and os.path.exists(path) and os.path.exists(side):
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


def resolve_scenes(args, tmpdir):
    """The scenes to measure, and notes on the suite scenes that are missing."""
    scenes, missing = [], []
    workdir = os.path.join(args.cache, "derived")
    names = suite_scenes.suite_names() if args.scenes == "suite" else \
        [s for s in args.scenes.split(",") if s]
    for name in names:
        if name.endswith(".dae"):
            if not os.path.exists(name):
                sys.exit(f"compare_cycles: no scene {name}")
            stem = os.path.splitext(os.path.basename(name))[0]
            scenes.append(Scene(stem, "", os.path.normpath(name), None, scene_key(name)))
            continue
        try:
            entry = suite_scenes.find(name)
        except KeyError as e:
            sys.exit(f"compare_cycles: {e.args[0]}")
        try:
            path, env = suite_scenes.resolve(entry, args.scenes_dir, args.scene_dir, workdir)
        except suite_scenes.MissingScene as e:
            missing.append((name, str(e)))
            log(f"{name}: skipped, {e}")
            continue
        env_px = read_rgb(env, tmpdir)[0].tobytes() if env else None
        scenes.append(Scene(name, entry.kind, path, env,
                            scene_key(path, env_px, entry.file_camera), entry.file_camera))
    return scenes, missing


# --------------------------------------------------------------------------
# Renders
# --------------------------------------------------------------------------

def render_cycles(args, scene, out, spp, seed, adaptive=None):
    """Renders with Cycles; returns its JSON line (dict)."""
    w, h = args.resolution
    cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "-P", os.path.join(ROOT, "tools", "cycles_world.py"), "--",
           "--peer-script", args.cycles_script, "--scene", scene.path, "--out", out,
           "--width", str(w), "--height", str(h), "--spp", str(spp),
           "--threads", str(args.threads),
           "--max-bounces", str(cycles_max_bounces(args.max_depth)),
           "--light-mode", "candela", "--seed", str(seed),
           # candela's emissive meshes emit from both faces (Material::emission)
           "--emitter-sides", "both"]
    if scene.env:
        cmd += ["--env-map", scene.env]
    if scene.file_camera:
        cmd += ["--camera", "collada"]
    if adaptive is not None:
        cmd += ["--adaptive", "--adaptive-threshold", str(adaptive)]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = next((l for l in p.stdout.splitlines() if l.startswith('{"tool": "cycles-peer"')), None)
    if p.returncode != 0 or line is None:
        raise RuntimeError(f"Cycles failed on {scene.path} (status {p.returncode}):\n"
                           + (p.stderr or p.stdout)[-2000:])
    return json.loads(line)


def render_candela(args, scene, out, extra, seed=CANDELA_SEED):
    """Renders with candela (-r, -m, -t fixed, plus `extra`); returns its JSON done line with
    the command's wall time ("process_seconds") added."""
    w, h = args.resolution
    cmd = [args.candela, "render", scene.path, "-r", str(w), str(h), "-m", str(args.max_depth),
           "-t", str(args.threads), "--seed", str(seed), "-f", out, "--progress", "json"]
    if scene.env:
        cmd += ["-e", scene.env]
    if scene.file_camera:
        cmd += ["--camera", "file"]
    cmd += extra
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - t0
    done = None
    for l in p.stdout.splitlines():
        if l.startswith("{") and '"event":"done"' in l:
            done = json.loads(l)
    if p.returncode != 0 or done is None:
        raise RuntimeError(f"candela failed on {scene.path} (status {p.returncode}): "
                           + " ".join(cmd) + "\n" + p.stderr[-2000:])
    done["command"] = cmd
    done["process_seconds"] = seconds
    return done


def child_cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_of(render):
    """Process CPU seconds (all threads) of one render command."""
    c0 = child_cpu_seconds()
    render()
    return child_cpu_seconds() - c0


class TimedRenders:
    """The timed renders of one scene, for --repeat. Each setting renders once where the
    measurement needs it (its image decides the ladder); rounds() then renders every setting
    again, in the order of the first round, --repeat - 1 times, and each setting keeps its
    fastest run. Renders of Cycles and candela thus alternate within every round, so that a
    slow spell of a shared machine slows both rather than one (the images of a seed are the
    same every time: only the times change)."""

    def __init__(self, args):
        self.args = args
        self.settings = []  # (render, seconds_of, on_faster)

    @staticmethod
    def timed(render):
        """One run of `render`, with the command's CPU seconds (all threads; includes start-up)
        under "command_cpu_seconds"."""
        c0 = child_cpu_seconds()
        info = render()
        info["command_cpu_seconds"] = child_cpu_seconds() - c0
        return info

    def first(self, render, seconds_of, on_faster):
        """Runs `render` once and returns its run; later rounds call on_faster(run) with any
        run faster than every earlier one of this setting."""
        info = self.timed(render)
        best = [seconds_of(info)]

        def again():
            run = self.timed(render)
            if seconds_of(run) < best[0]:
                best[0] = seconds_of(run)
                on_faster(run)

        self.settings.append(again)
        return info

    def rounds(self, log_prefix):
        for r in range(1, self.args.repeat):
            log(f"{log_prefix}: round {r + 1} of {self.args.repeat} (every timed render again)")
            for again in self.settings:
                again()


def references(args, scene):
    cy_path = find_reference(args, scene, args.ref_spp,
                             f"cycles-fixed-r{CYCLES_READING_VERSION}")
    cy_spp = int(cy_path.rsplit("spp-", 1)[0].rsplit("-", 1)[1])
    cy = cached(args, cy_path,
                lambda out: render_cycles(args, scene, out, cy_spp, REFERENCE_SEED))
    ca_path = find_reference(args, scene, args.candela_ref_spp, "candela-uniform-sobol",
                             args.refresh_candela)
    ca_spp = int(ca_path.rsplit("spp-", 1)[0].rsplit("-", 1)[1])
    binary = file_hash(args.candela)

    def render_reference(out):
        info = render_candela(
            args, scene, out, ["--adaptive", "none", "--sampler", "sobol", "-s", str(ca_spp)],
            seed=REFERENCE_SEED)
        info["candela_sha256"] = binary
        return info

    ca = cached(args, ca_path, render_reference, args.refresh_candela)
    # The cache key names the scene and the settings, not the renderer: a reference made before
    # a change to candela's images is still found. Say so; --refresh-candela renders it again.
    if ca.get("candela_sha256") != binary:
        log(f"{scene.name}: candela's reference {os.path.basename(ca_path)} was rendered by "
            "another candela binary; if candela's images changed since, run again with "
            "--refresh-candela")
    return cy_path, cy, cy_spp, ca_path, ca, ca_spp


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


def bracket(ladder, target):
    """The two ladder points of adjacent noise thresholds whose relMSE brackets `target`
    (higher error first), or None when no pair does."""
    pts = sorted(ladder, key=lambda p: -p["noise_threshold"])
    for a, b in zip(pts, pts[1:]):
        if a["relmse"] >= target >= b["relmse"] and a["relmse"] > b["relmse"]:
            return a, b
    return None


def candela_seconds(done):
    return done["time_s"]["build"] + done["time_s"]["render"]


def ray_rate(done):
    """Rays (camera, bounce and shadow) per second of the render phase."""
    r = done["time_s"]["render"]
    return (done["rays"] + done["shadow_rays"]) / r if r > 0 else None


def refs_noise_relmse(candela_ref_own, cycles_relmse, cycles_spp, cycles_ref_spp):
    """The relMSE of the references against each other that their own noise explains: the
    candela reference's own (from its variance) plus the Cycles reference's, estimated from a
    Cycles render of cycles_spp samples as falling like 1/spp."""
    return candela_ref_own + cycles_relmse * cycles_spp / cycles_ref_spp


def harness_notes(*cycles_infos):
    """What the Cycles peer script warned about (it renders without the thing it names)."""
    notes = []
    for info in cycles_infos:
        for w in info.get("warnings", []):
            if w not in notes:
                notes.append(w)
    return notes


def mean_difference(res):
    """candela's reference's image mean over Cycles' - 1, and the standard error of candela's
    side of it (from its variance channel, an upper bound under Sobol; Cycles' reference adds
    noise of its own that it does not report); None for results made before they were kept."""
    if "candela_ref_mean" not in res or not res["cycles_ref_mean"]:
        return None
    cy = res["cycles_ref_mean"]
    return res["candela_ref_mean"] / cy - 1.0, res["candela_ref_mean_se"] / cy


def mean_text(res):
    """The image means of the two references, as a phrase."""
    d = mean_difference(res)
    if d is None:
        return "image means not recorded"
    return (f"image means {res['candela_ref_mean']:.5g} / {res['cycles_ref_mean']:.5g} "
            f"(candela / Cycles - 1 = {100 * d[0]:+.3f} %, candela's side +- {100 * d[1]:.3f} %)")


def measure_references(args, scene, tmpdir):
    """The scene's two references (rendered or from the cache) and their agreement: the
    scene's result so far, and the references' pixels (Cycles', candela's)."""
    stem = scene.name
    cy_ref_path, cy_ref_info, cy_spp, ca_ref_path, ca_ref_info, ca_spp = references(args, scene)
    cy_ref, w, h = read_rgb(cy_ref_path, tmpdir)
    ca_ref, w2, h2 = read_rgb(ca_ref_path, tmpdir)
    if (w, h) != (w2, h2):
        raise RuntimeError(f"{stem}: the references differ in size")
    ca_var, _, _ = read_rgb(ca_ref_path, tmpdir, "variance.R,variance.G,variance.B")
    res = {"scene": stem, "kind": scene.kind, "file": scene.path, "env": scene.env,
           "key": scene.key, "refs_relmse": rel_mse(ca_ref, cy_ref),
           "candela_ref_own_relmse": rel_error_of_mean(ca_var, ca_ref),
           "candela_ref_mean": image_mean(ca_ref), "cycles_ref_mean": image_mean(cy_ref),
           "candela_ref_mean_se": std_err_of_mean(ca_var),
           "cycles_ref_spp": cy_spp, "candela_ref_spp": ca_spp,
           "cycles_ref": cy_ref_info, "candela_ref": ca_ref_info,
           "harness_notes": harness_notes(cy_ref_info)}
    log(f"{stem}: references agree to relMSE {res['refs_relmse']:.3g} (candela against Cycles); "
        f"the candela reference's own relMSE is at most {res['candela_ref_own_relmse']:.3g}; "
        f"{mean_text(res)}")
    for n in res["harness_notes"]:
        log(f"{stem}: Cycles peer script: {n}")
    return res, cy_ref, ca_ref


def start_up_cpu_seconds(args, scene, outdir):
    """Process CPU seconds of a 1-spp render of each renderer (Cycles', candela's): start-up,
    scene import, BVH build, image writing (and one sample). Subtracted from each render's
    process CPU seconds, it leaves the CPU seconds of sampling, which a shared machine's load
    changes far less than wall time."""
    log(f"{scene.name}: 1-spp renders (start-up CPU seconds)")
    one = os.path.join(outdir, f"{scene.name}-one.exr")
    cy_over = min(cpu_of(lambda: render_cycles(args, scene, one, 1, CYCLES_SEED))
                  for _ in range(OVERHEAD_RUNS))
    ca_over = min(cpu_of(lambda: render_candela(args, scene, one,
                                                ["--adaptive", "none", "-s", "1"]))
                  for _ in range(OVERHEAD_RUNS))
    return cy_over, ca_over


def measure_cycles(args, scene, tmpdir, outdir, timed, cy_over, cy_ref, ca_ref, res):
    """Cycles' timed renders: fixed spp (its error over --error-seeds seeds), then the adaptive
    settings. Returns one dict a render; adds the peer script's warnings to res."""
    stem = scene.name
    cycles = []
    settings = [("fixed", args.cycles_spp, None)] + [
        ("adaptive", spp, thr) for thr, spp in args.cycles_adaptive]
    for kind, spp, thr in settings:
        out = os.path.join(outdir, f"{stem}-cycles-{kind}-{spp}" + (f"-{thr}" if thr else "")
                           + ".exr")
        log(f"{stem}: Cycles {kind} {spp} spp" + (f", threshold {thr}" if thr else ""))
        c = {"kind": kind, "spp": spp, "threshold": thr}

        def cycles_times(info, c=c):
            c.update({"seconds": info["render_seconds"],
                      "pathtrace_seconds": info["cycles_pathtrace_seconds"],
                      "command_cpu_seconds": info["command_cpu_seconds"],
                      "cpu_seconds": info["command_cpu_seconds"] - cy_over})

        info = timed.first(
            lambda out=out, spp=spp, thr=thr: render_cycles(args, scene, out, spp, CYCLES_SEED,
                                                            thr),
            lambda i: i["render_seconds"], cycles_times)
        cycles_times(info)
        img, _, _ = read_rgb(out, tmpdir)
        figures = error_figures(img, cy_ref, ca_ref)
        if kind == "fixed":
            def cycles_seed(k, spp=spp):
                seed_out = os.path.join(outdir, f"{stem}-cycles-{kind}-{spp}-seed{k}.exr")
                log(f"{stem}: Cycles {kind} {spp} spp, seed {CYCLES_SEED + k} (error only)")
                render_cycles(args, scene, seed_out, spp, CYCLES_SEED + k)
                return seed_out
            figures = seed_figures(args, figures, cycles_seed, tmpdir, cy_ref, ca_ref)
        c.update(figures)
        # Equal-error times use each renderer's error against its own reference (for the fixed
        # render, the mean over the seeds: Cycles' error at that spp, not one render's).
        c["own_relmse"] = c["relmse"]
        cycles.append(c)
        res["harness_notes"] = harness_notes({"warnings": res["harness_notes"]}, info)
    return cycles


def judge_references(res, fixed):
    """Do the references agree as far as their noise allows? The Cycles reference's own relMSE
    is estimated from its fixed-spp render's (`fixed`), as 1/spp. Sets the result's
    refs_expected_relmse and refs_disagree."""
    expected = refs_noise_relmse(res["candela_ref_own_relmse"], fixed["relmse"], fixed["spp"],
                                 res["cycles_ref_spp"])
    res["refs_expected_relmse"] = expected
    res["refs_disagree"] = res["refs_relmse"] > REFS_DISAGREE_FACTOR * expected
    if res["refs_disagree"]:
        log(f"{res['scene']}: the references disagree: relMSE {res['refs_relmse']:.3g} against "
            f"{expected:.3g} from their noise")


def grow_ladder(ladder, thresholds, targets, run):
    """The noise thresholds of candela's ladder: `thresholds` (falling, rising cost) until one
    point reaches every target relMSE; then lower thresholds until one does, higher ones until
    one lies above every target (or sits at the first batch); then bisections of every bracket
    wider than LADDER_MAX_GAP. run(threshold) renders one and appends its point
    ({"noise_threshold", "relmse", "spp_mean", ...}) to `ladder`, which ends sorted by falling
    threshold."""
    for thr in thresholds:  # falling thresholds, rising cost: stop once below every target
        run(thr)
        if min(p["relmse"] for p in ladder) <= min(targets):
            break
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
    for target in targets:
        for _ in range(LADDER_MAX_BISECT):
            pair = bracket(ladder, target)
            if pair is None or pair[0]["relmse"] <= LADDER_MAX_GAP * pair[1]["relmse"]:
                break
            run(math.sqrt(pair[0]["noise_threshold"] * pair[1]["noise_threshold"]))
    ladder.sort(key=lambda p: -p["noise_threshold"])


def measure_ladder(args, scene, tmpdir, outdir, timed, ca_over, ca_ref, targets):
    """candela with its default settings over the noise-threshold ladder (grow_ladder), each
    point's relMSE against candela's reference. Returns the ladder."""
    stem = scene.name
    ladder = []

    def run(thr):
        out = os.path.join(outdir, f"{stem}-candela-nt{thr:.5g}.exr")
        log(f"{stem}: candela default, --noise-threshold {thr:.5g}")
        point = {"noise_threshold": thr}

        def ladder_times(done):
            point.update({"seconds": candela_seconds(done),
                          "process_seconds": done["process_seconds"],
                          "render_seconds": done["time_s"]["render"],
                          "build_seconds": done["time_s"]["build"],
                          "command_cpu_seconds": done["command_cpu_seconds"],
                          "cpu_seconds": done["command_cpu_seconds"] - ca_over})

        done = timed.first(lambda: render_candela(args, scene, out,
                                                  ["--noise-threshold", f"{thr:.6g}"]),
                           candela_seconds, ladder_times)
        ladder_times(done)
        img, _, _ = read_rgb(out, tmpdir)
        point.update({"spp_mean": done["spp_mean"], "relmse": rel_mse(img, ca_ref)})
        ladder.append(point)

    grow_ladder(ladder, args.ladder, targets, run)
    return ladder


def measure_fixed_spp(args, scene, tmpdir, outdir, timed, ca_over, cy_ref, ca_ref):
    """candela at Cycles' fixed spp: uniform (--adaptive none: per-sample error over
    --error-seeds seeds, uniform ray rate) and the default sampler spending the same budget (its
    ray rate and error), one after the other. Returns (uniform, default budget)."""
    stem, spp = scene.name, args.cycles_spp
    out = os.path.join(outdir, f"{stem}-candela-uniform-{spp}.exr")
    log(f"{stem}: candela --adaptive none -s {spp}, then the default sampler with -s {spp} "
        "--noise-threshold 0")
    uni = {"spp": spp}

    def uniform_times(done):
        uni.update({"seconds": candela_seconds(done), "process_seconds": done["process_seconds"],
                    "render_seconds": done["time_s"]["render"],
                    "command_cpu_seconds": done["command_cpu_seconds"],
                    "cpu_seconds": done["command_cpu_seconds"] - ca_over,
                    "ray_rate": ray_rate(done)})

    done = timed.first(lambda out=out: render_candela(
        args, scene, out, ["--adaptive", "none", "-s", str(spp)]), candela_seconds,
        uniform_times)
    uniform_times(done)
    img, _, _ = read_rgb(out, tmpdir)

    def candela_seed(k):
        seed_out = os.path.join(outdir, f"{stem}-candela-uniform-{spp}-seed{k}.exr")
        log(f"{stem}: candela --adaptive none -s {spp}, seed {CANDELA_SEED + k} (error only)")
        render_candela(args, scene, seed_out, ["--adaptive", "none", "-s", str(spp)],
                       seed=CANDELA_SEED + k)
        return seed_out
    uni.update(seed_figures(args, error_figures(img, cy_ref, ca_ref), candela_seed, tmpdir,
                            cy_ref, ca_ref))
    out = os.path.join(outdir, f"{stem}-candela-default-{spp}.exr")
    default_budget = {"spp": spp}

    def default_times(done):
        default_budget.update({"render_seconds": done["time_s"]["render"],
                               "ray_rate": ray_rate(done)})

    done = timed.first(lambda out=out: render_candela(
        args, scene, out, ["-s", str(spp), "--noise-threshold", "0"]), candela_seconds,
        default_times)
    default_times(done)
    img, _, _ = read_rgb(out, tmpdir)
    default_budget["spp_mean"] = done["spp_mean"]
    default_budget.update(error_figures(img, cy_ref, ca_ref))
    return uni, default_budget


def equal_error_times(cycles, ladder):
    """For each Cycles render, candela's time at its error (time_at_error over the ladder) in
    each of the ladder's times, and its ratio to Cycles' time of the same kind."""
    def at(c, field):
        return time_at_error([(p[field], p["relmse"]) for p in ladder], c["own_relmse"])

    for c in cycles:
        t, how = at(c, "seconds")
        c["candela_seconds"] = t
        c["candela_estimate"] = how
        c["ratio"] = t / c["seconds"]
        t, _ = at(c, "process_seconds")
        c["candela_process_seconds"] = t
        c["ratio_process"] = t / c["seconds"]
        t, _ = at(c, "render_seconds")
        c["candela_pathtrace_seconds"] = t
        c["ratio_pathtrace"] = t / c["pathtrace_seconds"] if c["pathtrace_seconds"] else None
        t, _ = at(c, "cpu_seconds")
        c["candela_cpu_seconds"] = t
        c["ratio_cpu"] = t / c["cpu_seconds"]


def per_sample_ratios(uni, fixed):
    """candela's uniform render against Cycles' fixed one at the same spp: time and error
    ratios, set in `uni`."""
    uni["time_per_sample_ratio"] = uni["seconds"] / fixed["seconds"]
    uni["cpu_time_ratio"] = uni["cpu_seconds"] / fixed["cpu_seconds"]
    uni["pathtrace_time_ratio"] = (uni["render_seconds"] / fixed["pathtrace_seconds"]
                                   if fixed["pathtrace_seconds"] else None)
    uni["error_ratio_equal_spp"] = uni["relmse"] / fixed["relmse"]
    uni["error_ratio_equal_spp_vs_candela_ref"] = (uni["relmse_vs_candela_ref"]
                                                   / fixed["relmse_vs_candela_ref"])


def measure_scene(args, scene, tmpdir, outdir):
    """Every figure of one scene (the steps above, in this order: each timed render's first
    run decides what is rendered next; --repeat's rounds follow them)."""
    res, cy_ref, ca_ref = measure_references(args, scene, tmpdir)
    if args.refs_only:
        return res
    cy_over, ca_over = start_up_cpu_seconds(args, scene, outdir)
    res.update({"cycles_overhead_cpu_seconds": cy_over, "candela_overhead_cpu_seconds": ca_over})
    timed = TimedRenders(args)
    cycles = measure_cycles(args, scene, tmpdir, outdir, timed, cy_over, cy_ref, ca_ref, res)
    judge_references(res, cycles[0])
    ladder = measure_ladder(args, scene, tmpdir, outdir, timed, ca_over, ca_ref,
                            [c["own_relmse"] for c in cycles])
    uni, default_budget = measure_fixed_spp(args, scene, tmpdir, outdir, timed, ca_over, cy_ref,
                                            ca_ref)
    timed.rounds(scene.name)
    equal_error_times(cycles, ladder)
    per_sample_ratios(uni, cycles[0])
    res.update({"cycles": cycles, "candela_ladder": ladder, "candela_uniform": uni,
                "candela_default_budget": default_budget})
    return res


# --------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------

def fmt(x, spec):
    return "-".rjust(int(spec.split(".")[0] or 0)) if x is None else format(x, spec)


def suite_rows(results):
    """One row per measured scene: the figures of the suite table (None where not measured)."""
    rows = []
    for r in results:
        if "candela_uniform" not in r:
            continue
        u, c, d = r["candela_uniform"], r["cycles"][0], r["candela_default_budget"]
        rate_ratio = (d["ray_rate"] / u["ray_rate"]
                      if d["ray_rate"] and u["ray_rate"] else None)
        rows.append({
            "scene": r["scene"], "kind": r.get("kind", ""),
            "notes": bool(r.get("harness_notes")), "disagree": bool(r.get("refs_disagree")),
            "candela_relmse": u["relmse"], "cycles_relmse": c["relmse"],
            "error_ratio": u["error_ratio_equal_spp"],
            "candela_relmse_own": u["relmse_vs_candela_ref"],
            "cycles_relmse_own": c["relmse_vs_candela_ref"],
            "error_ratio_own": u["error_ratio_equal_spp_vs_candela_ref"],
            "candela_tail": u["tail_share"], "cycles_tail": c["tail_share"],
            "default_relmse": d.get("relmse"), "default_tail": d.get("tail_share"),
            "rate_default": d["ray_rate"], "rate_uniform": u["ray_rate"],
            "rate_ratio": rate_ratio,
            "ratio_process": c["ratio_process"], "ratio_wall": c["ratio"],
            "estimate": c["candela_estimate"], "mean_difference": mean_difference(r)})
    return rows


def mean_cell(d):
    """The image-mean column of the suite table."""
    return "n/a" if d is None else f"{100 * d[0]:+.3f} % ({100 * d[1]:.3f} %)"


ESTIMATE_MARK = {"interpolated": "", "fastest": " (least)", "extrapolated": " (extrap.)"}


def markdown_table(results, spp, seeds=1):
    """The suite table of docs/performance.md (per-sample figures: means of `seeds` seeds)."""
    of = f"mean of {seeds} seeds' " if seeds > 1 else ""
    lines = [f"| kind of scene | scene | {of}relMSE at {spp} spp, candela / Cycles (ratio) | "
             "same against candela's reference | worst 1 % of pixels' share, candela / Cycles "
             f"| default sampler at a {spp}-spp budget: relMSE (worst 1 % share) "
             "| Mrays/s default / uniform (ratio) | **equal-error time / Cycles, whole process** "
             "| build + render | image mean, candela / Cycles - 1 (candela's s.e.) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for w in suite_rows(results):
        mark = ESTIMATE_MARK[w["estimate"]]
        lines.append(
            f"| {w['kind']}{' †' if w['notes'] else ''}{' ‡' if w['disagree'] else ''} | "
            f"{w['scene']} | "
            f"{w['candela_relmse']:.3g} / {w['cycles_relmse']:.3g} ({w['error_ratio']:.2f}) | "
            f"{w['candela_relmse_own']:.3g} / {w['cycles_relmse_own']:.3g} "
            f"({w['error_ratio_own']:.2f}) | "
            f"{100 * w['candela_tail']:.0f} % / {100 * w['cycles_tail']:.0f} % | "
            f"{fmt(w['default_relmse'], '.3g')} "
            f"({fmt(w['default_tail'] and 100 * w['default_tail'], '.0f')} %) | "
            f"{fmt(w['rate_default'] and w['rate_default'] / 1e6, '.1f')} / "
            f"{fmt(w['rate_uniform'] and w['rate_uniform'] / 1e6, '.1f')} "
            f"({fmt(w['rate_ratio'], '.2f')}) | "
            f"**{w['ratio_process']:.2f}**{mark} | {w['ratio_wall']:.2f}{mark} | "
            f"{mean_cell(w['mean_difference'])} |")
    return "\n".join(lines)


def markdown_notes(results, missing):
    """The lines under the suite table: each scene's references and the peer script's notes."""
    lines = ["References (Cycles / candela spp; relMSE of candela's against Cycles'; the candela "
             "reference's own relMSE, an upper bound): " + "; ".join(
                 f"{r['scene']} {r['cycles_ref_spp']} / {r['candela_ref_spp']}, "
                 f"{r['refs_relmse']:.2g}, {r['candela_ref_own_relmse']:.2g}" for r in results)
             + "."]
    for r in results:
        for n in r.get("harness_notes", []):
            lines.append(f"† {r['scene']}: the Cycles peer script: {n}.")
        if r.get("refs_disagree"):
            lines.append(f"‡ {r['scene']}: the references disagree (relMSE "
                         f"{r['refs_relmse']:.2g} against each other, "
                         f"{r['refs_expected_relmse']:.2g} from their noise): the renderers "
                         "do not render the same image, so the ratios compare different things.")
    for name, why in missing:
        lines.append(f"Not measured: {name} ({why}).")
    return "\n\n".join(lines)


def print_report(args, results, missing):
    w, h = args.resolution
    print(f"candela {args.candela} against Cycles ({args.blender}), {w}x{h}, -m {args.max_depth}, "
          f"{args.threads} threads; references: Cycles {args.ref_spp}+ spp, candela "
          f"{args.candela_ref_spp}+ spp uniform Sobol")
    for name, why in missing:
        print(f"skipped {name}: {why}")
    print()
    print("refs relMSE: candela's reference against Cycles'; own: the candela reference's own "
          "relMSE (upper bound, from its variance)")
    for r in results:
        print(f"  {r['scene']:22} refs relMSE {r['refs_relmse']:.3g}, own {r['candela_ref_own_relmse']:.3g}"
              f" (Cycles {r['cycles_ref_spp']} spp, candela {r['candela_ref_spp']} spp); "
              f"{mean_text(r)}")
        for n in r.get("harness_notes", []):
            print(f"  {'':22} † Cycles peer script: {n}")
    if args.refs_only:
        return
    spp = args.cycles_spp
    print()
    print(f"per sample at {spp} spp (candela --adaptive none, Cycles fixed) against Cycles' "
          "reference [against candela's]; tail = share of the squared error in the worst 1 % "
          "of pixels;\nray rates (Mrays/s, render phase) of the default sampler (-s "
          f"{spp} --noise-threshold 0) and the uniform one; equal-error time over Cycles' fixed "
          f"{spp} spp render_seconds,\ncandela's time as whole process and as build + render")
    print(f"{'scene':22} {'candela':>9} {'Cycles':>9} {'ratio':>6} {'[candela':>9} {'Cycles':>9} "
          f"{'ratio]':>6} {'tail ca':>7} {'tail cy':>7} {'Mr/s def':>8} {'uni':>6} {'ratio':>6} "
          f"{'process':>8} {'b+r':>6}")
    for wr in suite_rows(results):
        mark = (" †" if wr["notes"] else "") + (" ‡" if wr["disagree"] else "")
        print(f"{wr['scene'] + mark:22} {wr['candela_relmse']:9.3g} "
              f"{wr['cycles_relmse']:9.3g} {wr['error_ratio']:6.2f} "
              f"{wr['candela_relmse_own']:9.3g} {wr['cycles_relmse_own']:9.3g} "
              f"{wr['error_ratio_own']:6.2f} {100 * wr['candela_tail']:6.0f}% "
              f"{100 * wr['cycles_tail']:6.0f}% "
              f"{fmt(wr['rate_default'] and wr['rate_default'] / 1e6, '8.2f')} "
              f"{fmt(wr['rate_uniform'] and wr['rate_uniform'] / 1e6, '6.2f')} "
              f"{fmt(wr['rate_ratio'], '6.2f')} {wr['ratio_process']:8.3f} "
              f"{wr['ratio_wall']:6.3f}{ESTIMATE_MARK[wr['estimate']]}")
    print()
    print("against each Cycles render (each renderer against its own reference): seconds at "
          "equal error; wall = candela build + render; PT: path tracing alone; CPU: process CPU "
          "seconds less those of a 1-spp render")
    print(f"{'scene':22} {'Cycles render':>22} {'relMSE':>9} {'Cycles':>8} {'process':>8} "
          f"{'ratio':>6} {'wall':>7} {'ratio':>6} {'PT ratio':>8} {'CPU ratio':>9}")
    for r in results:
        for i, c in enumerate(r.get("cycles", [])):
            label = (f"fixed {c['spp']} spp" if c["kind"] == "fixed"
                     else f"adaptive {c['threshold']:g}/{c['spp']}")
            print(f"{r['scene'] if i == 0 else '':22} {label:>22} {c['own_relmse']:9.3g} "
                  f"{c['seconds']:8.2f} {c['candela_process_seconds']:8.2f} "
                  f"{c['ratio_process']:6.3f} {c['candela_seconds']:7.2f} {c['ratio']:6.3f} "
                  f"{fmt(c['ratio_pathtrace'], '8.3f')} {c['ratio_cpu']:9.3f}"
                  f"{ESTIMATE_MARK[c['candela_estimate']]}")
    print()
    print("candela ladder (default settings, --noise-threshold varied):")
    print(f"{'scene':22} {'threshold':>9} {'mean spp':>9} {'process s':>9} {'b+r s':>8} "
          f"{'CPU s':>8} {'relMSE':>9}")
    for r in results:
        for i, p in enumerate(r.get("candela_ladder", [])):
            print(f"{r['scene'] if i == 0 else '':22} {p['noise_threshold']:9.4g} "
                  f"{p['spp_mean']:9.1f} {p['process_seconds']:9.2f} {p['seconds']:8.2f} "
                  f"{p['cpu_seconds']:8.2f} {p['relmse']:9.3g}")
    print()
    print(f"time per sample at {spp} spp (candela --adaptive none against Cycles fixed):")
    print(f"{'scene':22} {'candela s':>9} {'Cycles s':>9} {'time ratio':>10} {'PT ratio':>8} "
          f"{'CPU ratio':>9}")
    for r in results:
        if "candela_uniform" not in r:
            continue
        u, c = r["candela_uniform"], r["cycles"][0]
        print(f"{r['scene']:22} {u['seconds']:9.2f} {c['seconds']:9.2f} "
              f"{u['time_per_sample_ratio']:10.3f} {fmt(u['pathtrace_time_ratio'], '8.3f')} "
              f"{u['cpu_time_ratio']:9.3f}")
    if any(r.get("harness_notes") for r in results):
        print("\n† the Cycles peer script rendered this scene without something it names above")
    for r in results:
        if r.get("refs_disagree"):
            print(f"‡ {r['scene']}: the references disagree: relMSE {r['refs_relmse']:.3g} "
                  f"against each other, {r['refs_expected_relmse']:.3g} from their noise")
    if args.markdown:
        print()
        print(markdown_table(results, spp, args.error_seeds))
        print()
        print(markdown_notes(results, missing))


def settings_of(args):
    """What a result depends on besides the scene: --resume keeps a result only if these match."""
    return {"version": RESULTS_VERSION, "candela_sha256": file_hash(args.candela),
            "cycles_script_sha256": file_hash(args.cycles_script),
            "cycles_world_sha256": file_hash(os.path.join(ROOT, "tools", "cycles_world.py")),
            "resolution": args.resolution, "max_depth": args.max_depth, "threads": args.threads,
            "ref_spp": args.ref_spp, "candela_ref_spp": args.candela_ref_spp,
            "cycles_spp": args.cycles_spp, "cycles_adaptive": args.cycles_adaptive,
            "ladder": args.ladder, "repeat": args.repeat, "error_seeds": args.error_seeds,
            "refs_only": args.refs_only}


def carried(previous, results):
    """The previous results (--resume) of scenes this run has not measured or kept (a scene
    whose file changed is this run's alone)."""
    names = {r["scene"] for r in results}
    return [r for r in previous.values() if r["scene"] not in names]


def suite_order(result):
    """Sort key: suite scenes in the suite's order, then any others by name."""
    names = suite_scenes.suite_names()
    name = result["scene"]
    return (names.index(name), "") if name in names else (len(names), name)


def write_json(args, settings, results, missing, load_start):
    meta = dict(settings, candela=args.candela, load_average_start=load_start,
                load_average_now=os.getloadavg(),
                time=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    tmp = args.json + ".tmp"
    with open(tmp, "w") as f:
        json.dump({"settings": meta, "scenes": results, "skipped": missing}, f, indent=1)
    os.replace(tmp, args.json)


def main(argv):
    args = parse_args(argv)
    if args.self_test:
        return self_test()
    if args.list:
        return suite_scenes.main(["list"])
    for tool in (args.blender, "oiiotool"):
        if shutil.which(tool) is None:
            sys.exit(f"compare_cycles: {tool} not found (apt-get install blender openimageio-tools)")
    if not os.access(args.candela, os.X_OK):
        sys.exit(f"compare_cycles: no candela binary at {args.candela} (--candela PATH)")
    if not os.path.exists(args.cycles_script):
        sys.exit(f"compare_cycles: no render_cycles.py at {args.cycles_script} (--cycles-script)")
    settings = settings_of(args)
    previous = {}
    if args.resume and os.path.exists(args.json):
        with open(args.json) as f:
            old = json.load(f)
        same = {k: v for k, v in old.get("settings", {}).items() if k in settings}
        if json.loads(json.dumps(settings)) == same:
            previous = {r["key"]: r for r in old.get("scenes", []) if "key" in r}
        else:
            log(f"{args.json}: other settings or binary; measuring every scene again")

    load_start = os.getloadavg()
    results = []
    with tempfile.TemporaryDirectory(prefix="compare_cycles.") as tmpdir:
        scenes, missing = resolve_scenes(args, tmpdir)
        outdir = args.keep or tmpdir
        os.makedirs(outdir, exist_ok=True)
        for scene in scenes:
            if scene.key in previous:
                log(f"{scene.name}: result kept from {args.json}")
                results.append(previous[scene.key])
                continue
            try:
                t0, load0 = time.strftime("%H:%M:%S", time.gmtime()), os.getloadavg()
                r = measure_scene(args, scene, tmpdir, outdir)
                r["measured_utc"] = [t0, time.strftime("%H:%M:%S", time.gmtime())]
                r["load_average"] = [load0, os.getloadavg()]
                results.append(r)
            except (RuntimeError, subprocess.CalledProcessError) as e:
                # One scene that a renderer cannot render does not end the suite.
                log(f"{scene.name}: failed: {e}")
                missing.append((scene.name, f"failed: {str(e)[-500:]}"))
            if args.json:
                write_json(args, settings, results + carried(previous, results), missing,
                           load_start)
    results = sorted(results + carried(previous, results), key=suite_order)
    load_end = os.getloadavg()
    print_report(args, results, missing)
    print()
    print("load average (1, 5, 15 min): at start %.2f %.2f %.2f, at end %.2f %.2f %.2f"
          % (load_start + load_end))
    if args.json:
        write_json(args, settings, results, missing, load_start)
    return 0


# --------------------------------------------------------------------------
# Self-test of the pure logic (run by CTest when python3 is there)
# --------------------------------------------------------------------------

class FakeRenders:
    """Stand-ins for the renderers, the image reader and the clock, for a whole measure_scene()
    without Blender, candela or oiiotool: a render's image is its reference plus an error that
    falls like 1/spp (Cycles, candela uniform) or like threshold^3 (the ladder), spread unevenly
    over four pixels; every render is logged in `calls`."""

    REF = [1.0, 0.5, 0.25] * 4

    def __init__(self):
        self.calls, self.images, self.clock = [], {}, 0.0

    def image(self, out, relmse, seed):
        # Pixel k of seed s carries a weight of 1 + k + s: the error lands unevenly.
        w = [1 + k + seed for k in range(4)]
        amp = math.sqrt(relmse * 4 / sum(w))
        self.images[out] = [v + amp * math.sqrt(w[i // 3] * (v * v + REL_MSE_EPS))
                            for i, v in enumerate(self.REF)]

    def read_rgb(self, path, tmpdir, channels="R,G,B"):
        if channels.startswith("variance"):
            return [1e-5] * 12, 4, 1
        return (self.images.get(path) or self.REF), 4, 1

    def references(self, args, scene):
        return ("cy.exr", {"warnings": ["no spot lights"]}, 2048, "ca.exr", {}, 2048)

    def render_cycles(self, args, scene, out, spp, seed, adaptive=None):
        self.calls.append(("cycles", spp, seed, adaptive))
        self.image(out, (0.2 if adaptive else 0.1) / spp, seed)
        self.clock += 0.5 + 0.01 * spp  # start-up, then the samples
        return {"render_seconds": 0.01 * spp, "cycles_pathtrace_seconds": 0.008 * spp,
                "warnings": ["adaptive note"] if adaptive else []}

    def render_candela(self, args, scene, out, extra, seed=CANDELA_SEED):
        self.calls.append(("candela", tuple(extra), seed))
        opts = dict(zip(extra[::2], extra[1::2]))
        if opts.get("--noise-threshold", "0") != "0":
            thr = float(opts["--noise-threshold"])
            relmse, spp = 10 * thr ** 3, 0.2 / thr ** 2
        else:
            spp = float(opts["-s"])
            relmse = 0.12 / spp
        self.image(out, relmse, seed)
        self.clock += 0.05 + 0.01 * spp  # start-up, then the samples
        return {"time_s": {"build": 0.05, "render": 0.01 * spp},
                "process_seconds": 0.1 + 0.01 * spp, "spp_mean": spp, "rays": 1000 * spp,
                "shadow_rays": 500 * spp}

    def child_cpu_seconds(self):
        return self.clock


def fake_measure(module, **settings):
    """measure_scene() of `module` (this file, or an earlier version of it) on FakeRenders:
    (the result, the renders in order)."""
    import types
    fake = FakeRenders()
    names = ("read_rgb", "references", "render_cycles", "render_candela", "child_cpu_seconds")
    saved = {n: getattr(module, n) for n in names + ("log",)}
    for n in names:
        setattr(module, n, getattr(fake, n))
    module.log = lambda msg: None
    args = types.SimpleNamespace(cycles_spp=64, cycles_adaptive=[(0.02, 256)], error_seeds=2,
                                 repeat=2, ladder=[0.05, 0.035, 0.025], refs_only=False)
    vars(args).update(settings)
    scene = Scene("s", "kind", "s.dae", None, "key")
    try:
        return module.measure_scene(args, scene, "tmp", "out"), fake.calls
    finally:
        for n, f in saved.items():
            setattr(module, n, f)


def check_measure_steps(close):
    """The steps of measure_scene(), each on its own and all together on FakeRenders."""
    this = sys.modules[__name__]
    saved_log, this.log = this.log, lambda msg: None
    try:
        check_steps(this, close)
    finally:
        this.log = saved_log


def check_steps(this, close):
    # The references' agreement: 1e-4 own + 1e-3 at 64 spp scaled to 1024 spp = 1.625e-4.
    res = {"scene": "s", "candela_ref_own_relmse": 1e-4, "cycles_ref_spp": 1024,
           "refs_relmse": 4.8e-4}
    judge_references(res, {"relmse": 1e-3, "spp": 64})
    assert close(res["refs_expected_relmse"], 1.625e-4) and not res["refs_disagree"]
    res["refs_relmse"] = 5e-4
    judge_references(res, {"relmse": 1e-3, "spp": 64})
    assert res["refs_disagree"]
    # The ladder on relMSE = threshold^3: 0.05 misses the lower target, one step down reaches
    # it, one step up passes the higher one, then each bracket wider than a factor of 2 (a
    # step of 1.4 is 2.74 in relMSE) is bisected once.
    ladder = []

    def run(thr, spp=None):
        ladder.append({"noise_threshold": thr, "relmse": thr ** 3,
                       "spp_mean": 1 / thr if spp is None else spp})

    grow_ladder(ladder, [0.05], [1e-4, 2e-4], run)
    order = [0.05, 0.05 / 1.4, 0.05 * 1.4, math.sqrt(0.05 * 0.05 / 1.4),
             math.sqrt(0.05 * 1.4 * 0.05)]
    assert len(ladder) == len(order) and all(close(p["noise_threshold"], t) for p, t in zip(
        ladder, sorted(order, reverse=True))), ladder
    # At the first batch (16 spp) a higher threshold is not rendered: the 2e-4 target stays
    # above the ladder.
    ladder.clear()
    grow_ladder(ladder, [0.05], [1e-4, 2e-4], lambda thr: run(thr, FIRST_BATCH_SPP))
    assert len(ladder) == 3 and all(close(p["noise_threshold"], t) for p, t in zip(
        ladder, [0.05, math.sqrt(0.05 * 0.05 / 1.4), 0.05 / 1.4])), ladder
    # The given thresholds stop at the first that reaches every target.
    ladder.clear()
    grow_ladder(ladder, [0.05, 0.04, 0.03], [1e-4], run)
    assert [p["noise_threshold"] for p in ladder] == [0.05, 0.04]
    # Equal-error times on relMSE = 1 / t (exact), each against Cycles' time of its kind.
    lad = [{"relmse": 1 / t, "seconds": t, "process_seconds": 2 * t, "render_seconds": t / 2,
            "cpu_seconds": 4 * t} for t in (1.0, 2.0, 4.0)]
    c = {"own_relmse": 1 / 3, "seconds": 6.0, "pathtrace_seconds": 0.0, "cpu_seconds": 24.0}
    equal_error_times([c], lad)
    assert close(c["candela_seconds"], 3) and c["candela_estimate"] == "interpolated"
    assert close(c["ratio"], 0.5) and close(c["ratio_process"], 1.0)
    assert close(c["candela_pathtrace_seconds"], 1.5) and c["ratio_pathtrace"] is None
    assert close(c["ratio_cpu"], 0.5)
    uni = {"seconds": 2.0, "cpu_seconds": 3.0, "render_seconds": 1.0, "relmse": 2e-3,
           "relmse_vs_candela_ref": 1e-3}
    per_sample_ratios(uni, {"seconds": 4.0, "cpu_seconds": 6.0, "pathtrace_seconds": 0.5,
                            "relmse": 1e-3, "relmse_vs_candela_ref": 2e-3})
    assert (uni["time_per_sample_ratio"], uni["cpu_time_ratio"], uni["pathtrace_time_ratio"],
            uni["error_ratio_equal_spp"], uni["error_ratio_equal_spp_vs_candela_ref"]) == (
                0.5, 0.5, 2.0, 2.0, 0.5)
    # The whole scene: the renders in the order the measurement needs them, then --repeat's
    # second round of every timed render.
    res, calls = fake_measure(this)
    nt = [c[1][1] for c in calls if c[0] == "candela" and c[1][0] == "--noise-threshold"]
    assert nt[:2] == ["0.05", "0.035"], nt  # 0.035 reaches both Cycles errors
    timed = [("cycles", 64, 0, None), ("cycles", 256, 0, 0.02)] + [
        ("candela", ("--noise-threshold", t), 1) for t in nt[:len(nt) // 2]] + [
        ("candela", ("--adaptive", "none", "-s", "64"), 1),
        ("candela", ("-s", "64", "--noise-threshold", "0"), 1)]
    assert calls[:4] == [("cycles", 1, 0, None)] * 2 + [
        ("candela", ("--adaptive", "none", "-s", "1"), 1)] * 2, calls[:4]
    # The second seeds of the fixed-spp comparison are rendered for their error alone.
    seeds = [("cycles", 64, 1, None), ("candela", ("--adaptive", "none", "-s", "64"), 2)]
    assert [c for c in calls[4:-len(timed)] if c not in seeds] == timed, calls
    assert calls[-len(timed):] == timed and all(calls.count(c) == 1 for c in seeds)
    assert res["harness_notes"] == ["no spot lights", "adaptive note"]
    fixed, adaptive = res["cycles"]
    assert close(fixed["relmse"], 0.1 / 64, 1e-6) and len(fixed["relmse_seeds"]) == 2
    assert close(adaptive["relmse"], 0.2 / 256, 1e-6) and "relmse_seeds" not in adaptive
    assert close(res["candela_uniform"]["error_ratio_equal_spp"], 1.2, 1e-6)
    assert [f"{p['noise_threshold']:.6g}" for p in res["candela_ladder"]] == sorted(
        nt[:len(nt) // 2], key=float, reverse=True)
    assert fixed["candela_estimate"] == "interpolated" and fixed["ratio"] > 0
    assert fake_measure(this, refs_only=True)[1] == []


def self_test():
    def close(a, b, tol=1e-9):
        return abs(a - b) <= tol * max(1.0, abs(a), abs(b))

    # The error figures of a render (the measures themselves: tools/image_error.py's self-test):
    # two pixels, one off by 1 in every channel of r = 1; against candela's reference of 2.
    r = array.array("f", [1, 1, 1, 0, 0, 0])
    x = array.array("f", [2, 2, 2, 0, 0, 0])
    f = error_figures(x, r, array.array("f", [2, 2, 2, 0, 0, 0]))
    assert close(f["relmse"], 3 / 1.01 / 6) and f["relmse_vs_candela_ref"] == 0
    assert f["tail_share"] == 1.0
    # Equal-error interpolation: on relMSE = 1 / t the interpolation is exact.
    pts = [(1.0, 1.0), (2.0, 0.5), (4.0, 0.25)]
    t, how = time_at_error(pts, 1 / 3)
    assert how == "interpolated" and close(t, 3.0), (t, how)
    assert time_at_error(pts, 2.0) == (1.0, "fastest")
    t, how = time_at_error(pts, 0.125)
    assert how == "extrapolated" and close(t, 8.0)
    # Reference agreement: 1e-4 own + 1e-3 at 64 spp scaled to 1024 spp.
    assert close(refs_noise_relmse(1e-4, 1e-3, 64, 1024), 1.625e-4)
    # --resume: earlier results of other scenes are carried, in the suite's order.
    prev = {"k1": {"key": "k1", "scene": "open-sky"}, "k2": {"key": "k2", "scene": "CBbunny"}}
    assert carried(prev, [{"key": "k3", "scene": "CBbunny"}]) == [prev["k1"]]
    order = sorted([{"scene": "x.dae"}, prev["k1"], prev["k2"]], key=suite_order)
    assert [r["scene"] for r in order] == ["CBbunny", "open-sky", "x.dae"]
    # Suite: every name unique, every entry with exactly one source.
    names = suite_scenes.suite_names()
    assert len(names) == len(set(names))
    for s in suite_scenes.SUITE:
        assert sum(x is not None for x in (s.cs184, s.repo, s.derive)) == 1, s.name
    # The sky map's mapping (spec 2.6): row 0 at the zenith, u = 1/4 towards +Z, 1/2 towards +X.
    d = suite_scenes.sky_direction(0, 0, 4, 1000)
    assert d[1] > 0.99999
    d = suite_scenes.sky_direction(0.5, 499.5, 4, 1000)  # u = 1/4, at the horizon
    assert close(d[2], 1.0, 1e-5), d
    d = suite_scenes.sky_direction(1.5, 499.5, 4, 1000)  # u = 1/2
    assert close(d[0], 1.0, 1e-5), d
    # The large mesh: the triangle count the suite promises, every index in range.
    verts, tris = suite_scenes.knot_mesh()
    assert len(tris) == 2 * suite_scenes.KNOT_SEGMENTS * suite_scenes.KNOT_SIDES >= 50000
    assert max(max(t) for t in tris) < len(verts)
    # The markdown table: one row per measured scene, the figures where they belong.
    res = [{"scene": "s", "kind": "k", "harness_notes": ["x"], "refs_disagree": False,
            "candela_uniform": {"relmse": 2e-3, "error_ratio_equal_spp": 2.0,
                                "relmse_vs_candela_ref": 1e-3,
                                "error_ratio_equal_spp_vs_candela_ref": 1.0,
                                "tail_share": 0.5, "ray_rate": 2e7},
            "cycles": [{"relmse": 1e-3, "relmse_vs_candela_ref": 1e-3, "tail_share": 0.25,
                        "ratio_process": 0.5, "ratio": 0.4, "candela_estimate": "interpolated"}],
            "candela_default_budget": {"ray_rate": 1e7, "relmse": 1.5e-3, "tail_share": 0.2}},
           {"scene": "refs only"}]
    table = markdown_table(res, 64).splitlines()
    assert len(table) == 3, table
    assert table[2] == ("| k † | s | 0.002 / 0.001 (2.00) | 0.001 / 0.001 (1.00) | 50 % / 25 % "
                        "| 0.0015 (20 %) | 10.0 / 20.0 (0.50) | **0.50** | 0.40 | n/a |"), table[2]
    res[0].update({"candela_ref_mean": 1.002, "cycles_ref_mean": 1.0,
                   "candela_ref_mean_se": 0.0005})
    assert markdown_table(res, 64).splitlines()[2].endswith(
        "| **0.50** | 0.40 | +0.200 % (0.050 %) |"), markdown_table(res, 64)
    assert markdown_table(res, 64, 4).splitlines()[0].startswith(
        "| kind of scene | scene | mean of 4 seeds' relMSE at 64 spp")
    # Bounce limits: candela's direct light (-m 1) is Cycles' max_bounces 0.
    assert cycles_max_bounces(1) == 0 and cycles_max_bounces(8) == 7
    try:
        cycles_max_bounces(0)
        raise AssertionError("-m 0 must be refused")
    except ValueError:
        pass
    # Seeds: every figure averaged, the per-seed relMSE kept.
    m = mean_figures([{"relmse": 1.0, "tail_share": 0.5}, {"relmse": 3.0, "tail_share": 0.7}])
    assert m["relmse"] == 2.0 and close(m["tail_share"], 0.6) and m["relmse_seeds"] == [1.0, 3.0]
    # The bracket of a target: adjacent thresholds, higher error first; none outside the ladder.
    lad = [{"noise_threshold": 0.1, "relmse": 0.2}, {"noise_threshold": 0.05, "relmse": 0.01},
           {"noise_threshold": 0.07, "relmse": 0.05}]
    assert [p["noise_threshold"] for p in bracket(lad, 0.03)] == [0.07, 0.05]
    assert [p["noise_threshold"] for p in bracket(lad, 0.1)] == [0.1, 0.07]
    assert bracket(lad, 0.5) is None and bracket(lad, 0.001) is None
    res[0].update({"cycles_ref_spp": 2048, "candela_ref_spp": 1024, "refs_relmse": 1.234e-4,
                   "candela_ref_own_relmse": 5e-5})
    notes = markdown_notes(res[:1], [("m", "not found")]).split("\n\n")
    assert notes == ["References (Cycles / candela spp; relMSE of candela's against Cycles'; the "
                     "candela reference's own relMSE, an upper bound): s 2048 / 1024, 0.00012, "
                     "5e-05.", "† s: the Cycles peer script: x.", "Not measured: m (not found)."
                     ], notes
    check_measure_steps(close)
    print("compare_cycles self-test: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
