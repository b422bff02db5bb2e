#!/usr/bin/env python3
"""Refining a finished render, measured on the performance suite's scenes.

For each scene: a render to --noise-threshold FIRST with --keep-checkpoint, its refinement
(`candela render --resume CKPT --noise-threshold SECOND`) and a direct render to SECOND. Prints
per scene the refinement's predicted and taken render time (and how far off the prediction
was), the refinement's time against the direct render's minus the first render's (whole
process, and render phase), and whether the refined image equals the direct one pixel for pixel
(`idiff -fail 0`). With --repeat N every figure is the median of N rounds.

Run from the repository root:
    python3 tools/refine_bench.py --candela build/candela [--scenes a,b] [--repeat 3]
Needs a built candela and idiff (openimageio-tools); the course scenes are read from
../shared/scenes/cs184 (scenes that need them are skipped without them).
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import suite_scenes  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse_args(argv):
    p = argparse.ArgumentParser(prog="tools/refine_bench.py", description=__doc__.split("\n")[0])
    p.add_argument("--candela", default=os.path.join(ROOT, "build", "candela"))
    p.add_argument("--scenes", default="suite", help="suite names, comma-separated (default: all)")
    p.add_argument("--scenes-dir", default=os.path.join(ROOT, "..", "shared", "scenes", "cs184"))
    p.add_argument("-r", "--resolution", nargs=2, type=int, default=[480, 360])
    p.add_argument("-m", "--max-depth", type=int, default=8)
    p.add_argument("-t", "--threads", type=int, default=2)
    p.add_argument("--first", type=float, default=0.04, help="the first render's noise threshold")
    p.add_argument("--second", type=float, default=0.02, help="the refined noise threshold")
    p.add_argument("-s", "--spp", type=int, default=None,
                   help="budget of all three renders (a scene whose first render spends the "
                   "default budget before its threshold has nothing left to refine)")
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--json", default=None, metavar="FILE", help="also write the figures here")
    return p.parse_args(argv)


def run(cmd):
    """Runs a candela command with --progress json; its done line plus the process's wall time."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd + ["--progress", "json"], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    done = next((json.loads(l) for l in p.stdout.splitlines()
                 if l.startswith("{") and '"event":"done"' in l), None)
    if p.returncode != 0 or done is None:
        sys.exit(f"refine_bench: failed (status {p.returncode}): {' '.join(cmd)}\n{p.stderr[-1500:]}")
    done["process_seconds"] = wall
    return done


def one_round(args, path, env, camera_file, work):
    w, h = args.resolution
    base = [args.candela, "render", path, "-r", str(w), str(h), "-m", str(args.max_depth),
            "-t", str(args.threads)]
    if args.spp:
        base += ["-s", str(args.spp)]
    if env:
        base += ["-e", env]
    if camera_file:
        base += ["--camera", "file"]
    refined = os.path.join(work, "refined.exr")
    direct = os.path.join(work, "direct.exr")
    first = run(base + ["--noise-threshold", str(args.first), "--keep-checkpoint", "-f", refined])
    if first.get("stop") != "noise_threshold":
        sys.exit(f"refine_bench: {path}: the first render stopped before noise "
                 f"{args.first} ({first.get('stop')}); give a larger -s")
    refine = run([args.candela, "render", "--resume", refined + ".ckpt", "-t", str(args.threads),
                  "--noise-threshold", str(args.second)])
    whole = run(base + ["--noise-threshold", str(args.second), "-f", direct])
    same = subprocess.run(["idiff", "-fail", "0", "-warn", "0", refined, direct],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0
    return {
        "predicted": refine.get("predicted_render_s"),
        "refine_render": refine["time_s"]["render"],
        "refine_process": refine["process_seconds"],
        "diff_process": whole["process_seconds"] - first["process_seconds"],
        "diff_render": whole["time_s"]["render"] - first["time_s"]["render"],
        "direct_process": whole["process_seconds"],
        "identical": same,
    }


def main(argv):
    args = parse_args(argv)
    for tool in (args.candela, "idiff"):
        if shutil.which(tool) is None and not os.path.exists(tool):
            sys.exit(f"refine_bench: {tool} not found")
    names = suite_scenes.suite_names() if args.scenes == "suite" else args.scenes.split(",")
    results = []
    print(f"load average at start: {' '.join(open('/proc/loadavg').read().split()[:3])}", flush=True)
    with tempfile.TemporaryDirectory(prefix="refine-bench-") as work:
        for name in names:
            entry = suite_scenes.find(name)
            try:
                path, env = suite_scenes.resolve(entry, args.scenes_dir,
                                                 [os.path.join(ROOT, "scenes")], work)
            except suite_scenes.MissingScene as e:
                print(f"{name}: skipped, {e}")
                continue
            rounds = [one_round(args, path, env, entry.file_camera, work)
                      for _ in range(args.repeat)]
            med = {k: statistics.median(r[k] for r in rounds)
                   for k in rounds[0] if k != "identical" and rounds[0][k] is not None}
            med["identical"] = all(r["identical"] for r in rounds)
            med["scene"] = name
            results.append(med)
    print(f"load average at end: {' '.join(open('/proc/loadavg').read().split()[:3])}")
    print(f"\n{args.resolution[0]}x{args.resolution[1]}, -m {args.max_depth}, -t {args.threads}, "
          f"noise threshold {args.first} refined to {args.second}; medians of {args.repeat}\n")
    print("| scene | predicted / taken render s (error) | refinement: whole process / render "
          "| direct - first: whole process / render | refined = direct |")
    print("|---|---|---|---|---|")
    for r in results:
        # As the stats block gives it: (taken - predicted) / predicted.
        off = (r["refine_render"] / r["predicted"] - 1) if r.get("predicted") else None
        print(f"| {r['scene']} | {r.get('predicted', float('nan')):.2f} / "
              f"{r['refine_render']:.2f} ({'-' if off is None else f'{100 * off:+.0f} %'}) | "
              f"{r['refine_process']:.2f} / {r['refine_render']:.2f} | "
              f"{r['diff_process']:.2f} / {r['diff_render']:.2f} | "
              f"{'yes' if r['identical'] else 'NO'} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0 if all(r["identical"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
