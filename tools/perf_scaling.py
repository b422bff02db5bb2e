#!/usr/bin/env python3
"""How candela's render cost grows: with resolution, samples per pixel, threads and triangles.

    python3 tools/perf_scaling.py [--candela build/candela] [--scene SCENE] [--quick]

Every render is uniform (--adaptive none, Sobol) so that its work is fixed, and is timed by
candela itself (the render phase of `--progress json`'s final line, which leaves out start-up,
loading, the build and writing). Peak memory is the process's, as candela reports it. The
triangle series renders `box:sphere:N` (a tessellated sphere of about N triangles in a lit open
box) with `candela bench --render`, which also gives the fraction of the raw-Embree ceiling
reached at each size. Prints Markdown tables; the load average is printed before and after,
since other work on the machine slows every figure.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile


def load_average():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def render(candela, scene, width, height, spp, threads, depth, out):
    cmd = [candela, "render", scene, "-r", str(width), str(height), "-s", str(spp),
           "-m", str(depth), "-t", str(threads), "--adaptive", "none", "--sampler", "sobol",
           "-q", "--progress", "json", "-f", out]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"perf_scaling: {' '.join(cmd)} failed: {p.stderr.strip()}")
    done = [json.loads(l) for l in p.stdout.splitlines() if '"event":"done"' in l]
    if not done:
        sys.exit(f"perf_scaling: no final progress line from {' '.join(cmd)}")
    d = done[-1]
    return d["time_s"]["render"], d["peak_memory_bytes"]


def bench(candela, spec, spp, threads):
    cmd = [candela, "bench", "--render", "--procedural", spec, "-r", "320", "240", "-s",
           str(spp), "-t", str(threads), "--render-rounds", "1", "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"perf_scaling: {' '.join(cmd)} failed: {p.stderr.strip()}")
    return json.loads(p.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--candela", default="build/candela")
    ap.add_argument("--scene", default="../shared/scenes/cs184/CBbunny.dae")
    ap.add_argument("--depth", type=int, default=8)
    ap.add_argument("--quick", action="store_true", help="smaller series (a smoke run)")
    args = ap.parse_args()
    if not os.path.exists(args.scene):
        sys.exit(f"perf_scaling: {args.scene} not found (give --scene)")
    print(f"load average before: {load_average()}\n")
    tmp = tempfile.mkdtemp(prefix="candela-scaling-")
    out = os.path.join(tmp, "img.exr")

    print("### Triangles (box:sphere:N, 320x240, 8 spp, -m 8, 2 threads; bench --render)\n")
    print("| triangles | render s | Mrays/s | raw Embree ceiling s | of ceiling | peak MiB |")
    print("|---|---|---|---|---|---|")
    counts = [10000, 100000] if args.quick else [10000, 100000, 1000000, 5000000]
    for n in counts:
        rep = bench(args.candela, f"box:sphere:{n}", 8, 0)
        row = rep["rows"][0]
        rays = row["camera_rays"] + row["bounce_rays"] + row["shadow_rays"]
        # Largest peak of any finished child: this series runs first and its sizes grow, so it
        # is this run's (the scene, candela's Embree scene and the raw loops' second one).
        peak_mib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        print(f"| {rep['triangles']} | {row['render_seconds']:.3f} | "
              f"{rays / row['render_seconds'] * 1e-6:.2f} | {row['ceiling_seconds']:.3f} | "
              f"{100 * row['fraction_of_ceiling']:.1f}% | {peak_mib:.0f} |")
    print()
    base_spp = 4 if args.quick else 16
    print(f"### Resolution ({args.scene}, {base_spp} spp, -m {args.depth}, 2 threads)\n")
    print("| resolution | pixels | render s | s per Mpixel-sample | peak MiB |")
    print("|---|---|---|---|---|")
    sizes = [(160, 120), (320, 240)] if args.quick else [(160, 120), (320, 240), (640, 480),
                                                         (1280, 960)]
    for w, h in sizes:
        t, mem = render(args.candela, args.scene, w, h, base_spp, 2, args.depth, out)
        print(f"| {w}x{h} | {w*h} | {t:.3f} | {t / (w*h*base_spp/1e6):.3f} | "
              f"{mem/2**20:.1f} |")

    print(f"\n### Samples per pixel ({args.scene}, 320x240, -m {args.depth}, 2 threads)\n")
    print("| spp | render s | s per spp |")
    print("|---|---|---|")
    for spp in ([4, 16] if args.quick else [4, 16, 64, 256]):
        t, _ = render(args.candela, args.scene, 320, 240, spp, 2, args.depth, out)
        print(f"| {spp} | {t:.3f} | {t/spp:.4f} |")

    print(f"\n### Threads ({args.scene}, 320x240, {base_spp * 4} spp, -m {args.depth})\n")
    print("| threads | render s | speed-up |")
    print("|---|---|---|")
    t1, _ = render(args.candela, args.scene, 320, 240, base_spp * 4, 1, args.depth, out)
    t2, _ = render(args.candela, args.scene, 320, 240, base_spp * 4, 2, args.depth, out)
    print(f"| 1 | {t1:.3f} | 1.00 |")
    print(f"| 2 | {t2:.3f} | {t1/t2:.2f} |")

    print(f"\nload average after: {load_average()}")


if __name__ == "__main__":
    main()
