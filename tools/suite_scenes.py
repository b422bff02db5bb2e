#!/usr/bin/env python3
"""The scenes of the performance suite (`tools/compare_cycles.py`) and the files it derives.

One scene of every kind the suite measures. Three sources:

  * the course scenes in `../shared/scenes/cs184` (read in place, never copied);
  * candela's own scenes in `scenes/` (a scene directory can be overridden or added to);
  * files this module writes at run time into a work directory: the rough-copper bunny (the
    course's CBbunny with the bunny's material swapped for a microfacet copper:
    tools/scene_writer.py), the large mesh (a generated torus-knot tube of 115,200 triangles in
    a box), the many-kinds-of-light scene (tools/light_kinds.py) and the sky map of the open
    scene. Their content depends only on these scripts (and on CBbunny.dae), so a cache keyed
    by the file's hash stays valid from run to run.

Standalone: `python3 tools/suite_scenes.py list` prints the suite; `python3 tools/suite_scenes.py
make DIR` writes the derived files into DIR (to render them by hand).
"""

import math
import os
import struct
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import light_kinds  # noqa: E402  (the many-kinds-of-light scene, beside this file)
import scene_writer  # noqa: E402  (COLLADA text, the copper bunny)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class MissingScene(Exception):
    """A suite scene whose file is not there (a scene not written yet, no shared scenes)."""


class SuiteScene:
    """One scene of the suite: its name (for --scenes), the kind it stands for, where it comes
    from (exactly one of cs184, repo, derive), its environment map, and whether both renderers
    take the file's camera pose instead of the course's framing (candela --camera file, the
    Cycles peer script --camera collada)."""

    def __init__(self, name, kind, cs184=None, repo=None, derive=None, env=None,
                 file_camera=False):
        self.name, self.kind = name, kind
        self.cs184, self.repo, self.derive, self.env = cs184, repo, derive, env
        self.file_camera = file_camera


# --------------------------------------------------------------------------
# The large mesh
# --------------------------------------------------------------------------

# Torus knot (P, Q) tube: SEGMENTS quads along the knot, SIDES around the tube, two triangles
# each: 2 * 600 * 96 = 115,200 triangles, above the suite's 50k floor for a "large mesh".
KNOT_P, KNOT_Q = 2, 3
KNOT_SEGMENTS, KNOT_SIDES = 600, 96
KNOT_SCALE = 0.25      # the knot's centre line spans radius 0.25 * (2 +- 1) m
KNOT_TUBE = 0.09       # tube radius, m
KNOT_CENTRE_Z = 0.75   # height of the knot's centre above the floor, m


def knot_mesh():
    """Vertices (x, y, z) and triangles (i, j, k) of the torus-knot tube, Z up."""
    verts, tris = [], []
    for s in range(KNOT_SEGMENTS):
        t = 2 * math.pi * s / KNOT_SEGMENTS
        cq, sq, cp, sp = (math.cos(KNOT_Q * t), math.sin(KNOT_Q * t), math.cos(KNOT_P * t),
                          math.sin(KNOT_P * t))
        c = [KNOT_SCALE * (2 + cq) * cp, KNOT_SCALE * (2 + cq) * sp,
             KNOT_CENTRE_Z - KNOT_SCALE * sq]
        # Tangent (derivative of the centre line); it is never vertical for a (2, 3) knot, so
        # the frame from its cross product with +Z is defined everywhere and periodic in t.
        d = [KNOT_SCALE * (-KNOT_Q * sq * cp - KNOT_P * (2 + cq) * sp),
             KNOT_SCALE * (-KNOT_Q * sq * sp + KNOT_P * (2 + cq) * cp),
             -KNOT_SCALE * KNOT_Q * cq]
        b = [d[1], -d[0], 0.0]
        bl = math.hypot(b[0], b[1])
        b = [b[0] / bl, b[1] / bl, 0.0]
        n = scene_writer.cross(b, scene_writer.normalize(d))
        for k in range(KNOT_SIDES):
            a = 2 * math.pi * k / KNOT_SIDES
            ca, sa = math.cos(a), math.sin(a)
            verts.append([c[i] + KNOT_TUBE * (ca * n[i] + sa * b[i]) for i in range(3)])
    for s in range(KNOT_SEGMENTS):
        s1 = (s + 1) % KNOT_SEGMENTS
        for k in range(KNOT_SIDES):
            k1 = (k + 1) % KNOT_SIDES
            a, b, c, d = (s * KNOT_SIDES + k, s1 * KNOT_SIDES + k, s1 * KNOT_SIDES + k1,
                          s * KNOT_SIDES + k1)
            tris += [(a, b, c), (a, c, d)]
    return verts, tris


def large_mesh():
    """COLLADA text of the large-mesh scene: a diffuse box (floor, ceiling, back wall, red left
    and blue right wall; open at the front like the course's Cornell boxes) 2 m wide, deep and
    high, lit by a 0.6 m square CGL area light under the ceiling, holding the torus-knot tube
    (diffuse, smooth normals computed by the renderer: the file has no NORMAL input). Z up;
    the camera looks along +Y, and renderers frame the scene by the course rule."""
    walls = {  # name: (albedo, corners)
        "floor": ("0.6 0.6 0.6", [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]),
        "ceiling": ("0.6 0.6 0.6", [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)]),
        "back": ("0.6 0.6 0.6", [(-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)]),
        "left": ("0.6 0.2 0.2", [(-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)]),
        "right": ("0.2 0.2 0.6", [(1, -1, 0), (1, -1, 2), (1, 1, 2), (1, 1, 0)]),
    }
    verts, tris = knot_mesh()
    effects = "".join(scene_writer.effect(n, rgb) for n, (rgb, _) in walls.items())
    effects += scene_writer.effect("knot", "0.75 0.6 0.35")
    names = list(walls) + ["knot"]
    materials = "".join(scene_writer.material(n) for n in names)
    meshes = [(n, c, [(0, 1, 2), (0, 2, 3)]) for n, (_, c) in walls.items()]
    meshes.append(("knot", verts, tris))
    geometries = "".join(scene_writer.mesh(n, v, t, f"{n}-material", p_on_own_line=True)
                         for n, v, t in meshes)
    nodes = "".join(scene_writer.node(n, f"{n}-mesh", f"{n}-material", n) for n in names)
    comment = (f"large-mesh.dae: written by tools/suite_scenes.py (do not edit). A (2, 3) "
               f"torus-knot tube of\n     {len(tris)} triangles in a diffuse box lit by one CGL "
               "area light.")
    light = ('    <light id="panel" name="panel"><technique_common><point><color sid="color">'
             '10 10 10</color>\n      </point></technique_common>\n'
             '      <extra><technique profile="CGL"><area><color sid="color">12 12 12</color>'
             '</area>\n      </technique></extra></light>\n')
    nodes += ('      <node id="camera-node" name="camera-node">\n'
              '        <matrix sid="transform">1 0 0 0 0 0 -1 -3 0 1 0 0 0 0 0 1</matrix>\n'
              '        <instance_camera url="#camera"/></node>\n'
              '      <node id="panel-node" name="panel-node">\n'
              '        <matrix sid="transform">0.6 0 0 0 0 0.6 0 0 0 0 1 1.98 0 0 0 1</matrix>\n'
              '        <instance_light url="#panel"/></node>\n')
    return scene_writer.document(comment, "Z_UP", 49.13434, 0.1, light, effects, materials,
                                 geometries, nodes)


# --------------------------------------------------------------------------
# The sky map of the open scene
# --------------------------------------------------------------------------

SKY_WIDTH, SKY_HEIGHT = 256, 128
# Unit direction towards the sun glow of the sky map (Y up). scenes/open-sky.dae's directional
# light shines from the same direction.
SUN_DIRECTION = (0.48, 0.6, -0.64)


def sky_direction(i, j, w, h):
    """Direction of the centre of pixel (i, j) of a w x h lat-long map, row 0 at the zenith:
    the mapping of the scene-format spec (2.6), which candela's -e follows."""
    phi = 2 * math.pi * (i + 0.5) / w
    theta = math.pi * (j + 0.5) / h
    return (math.cos(phi - math.pi) * math.sin(theta), math.cos(theta),
            -math.sin(phi - math.pi) * math.sin(theta))


def sky_radiance(d):
    """RGB radiance of the sky in direction d: a blue gradient above the horizon, a sun glow
    (peak about 60, a few degrees wide) with a broad halo, and a dark ground below."""
    if d[1] <= 0:
        return (0.08, 0.07, 0.06)
    c = sum(a * b for a, b in zip(d, SUN_DIRECTION))
    glow = 60.0 * math.exp((c - 1) / 0.002) + 1.5 * math.exp((c - 1) / 0.05)
    up = math.sqrt(d[1])
    base = [h + (z - h) * up for h, z in zip((0.9, 0.95, 1.0), (0.2, 0.35, 0.8))]
    return tuple(b + glow * s for b, s in zip(base, (1.0, 0.9, 0.75)))


def write_sky_map(path):
    """Writes the sky map as OpenEXR (through a PFM and oiiotool, which the suite needs
    anyway). PFM stores the bottom row first; the EXR has the zenith in its top row."""
    pfm = path + ".pfm"
    rows = []
    for j in reversed(range(SKY_HEIGHT)):
        rows.append(struct.pack(f"<{3 * SKY_WIDTH}f", *[
            x for i in range(SKY_WIDTH)
            for x in sky_radiance(sky_direction(i, j, SKY_WIDTH, SKY_HEIGHT))]))
    with open(pfm, "wb") as f:
        f.write(f"PF\n{SKY_WIDTH} {SKY_HEIGHT}\n-1.0\n".encode("ascii"))
        f.write(b"".join(rows))
    subprocess.run(["oiiotool", "--nosoftwareattrib", pfm, "-d", "float", "--eraseattrib", ".*",
                    "-o", path],
                   check=True, stdout=subprocess.DEVNULL)
    os.remove(pfm)


# --------------------------------------------------------------------------
# The suite
# --------------------------------------------------------------------------

SUITE = [
    SuiteScene("CBspheres_lambertian", "diffuse Cornell box (spheres)",
               cs184="CBspheres_lambertian.dae"),
    SuiteScene("CBbunny", "diffuse Cornell box (bunny)", cs184="CBbunny.dae"),
    SuiteScene("CBspheres", "mirror + glass spheres", cs184="CBspheres.dae"),
    SuiteScene("rough-metal", "rough-metal spheres", repo="rough-metal.dae"),
    SuiteScene("copper-bunny", "rough-copper bunny in a box",
               derive=("CBbunny.dae", "copper-bunny.dae", scene_writer.copper_bunny)),
    SuiteScene("mirror-coil", "mirror coil", repo="mirror-coil.dae"),
    SuiteScene("large-mesh", "large mesh (115k triangles)",
               derive=(None, "large-mesh.dae", large_mesh)),
    SuiteScene("open-sky", "open scene: ambient + directional + environment",
               repo="open-sky.dae", env=("open-sky-sky.exr", write_sky_map)),
    # Eight rooms side by side: the framed camera stands too far off (the file says so).
    SuiteScene("many-lights", "many lights (120 point lights in 8 rooms)", repo="many-lights.dae",
               file_camera=True),
    # Rectangles, points, spheres and tetrahedra in awkward places (tools/light_kinds.py).
    SuiteScene("light-kinds", "many kinds of light (177; rough metal, rough glass)",
               derive=(None, "light-kinds.dae", light_kinds.light_kinds), file_camera=True),
]


def suite_names():
    return [s.name for s in SUITE]


def find(name):
    for s in SUITE:
        if s.name == name:
            return s
    raise KeyError(f"no suite scene {name!r} (the suite: {', '.join(suite_names())})")


def _write_if_changed(path, text):
    """Writes text to path unless the file already holds it (keeps its time stamp)."""
    data = text.encode("utf-8")
    if os.path.exists(path):
        with open(path, "rb") as f:
            if f.read() == data:
                return
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def resolve(scene, cs184_dir, scene_dirs, workdir):
    """(scene file, environment map or None) of a suite scene. Derived files go to workdir.
    scene_dirs are searched in order for candela's own scenes. Raises MissingScene."""
    if scene.cs184 is not None:
        path = os.path.join(cs184_dir, scene.cs184)
        if not os.path.exists(path):
            raise MissingScene(f"{path} not found (the course scenes, --scenes-dir)")
    elif scene.repo is not None:
        tried = [os.path.join(d, scene.repo) for d in scene_dirs]
        path = next((p for p in tried if os.path.exists(p)), None)
        if path is None:
            raise MissingScene(f"{scene.repo} not found in {', '.join(scene_dirs)} (--scene-dir)")
    else:
        source, out, make = scene.derive
        os.makedirs(workdir, exist_ok=True)
        if source is None:
            text = make()
        else:
            src = os.path.join(cs184_dir, source)
            if not os.path.exists(src):
                raise MissingScene(f"{src} not found (the course scenes, --scenes-dir)")
            with open(src, encoding="utf-8") as f:
                text = make(f.read())
        path = os.path.join(workdir, out)
        _write_if_changed(path, text)
    env = None
    if scene.env is not None:
        name, make = scene.env
        os.makedirs(workdir, exist_ok=True)
        env = os.path.join(workdir, name)
        if not os.path.exists(env):
            make(env + ".tmp.exr")
            os.replace(env + ".tmp.exr", env)
    return os.path.normpath(path), env


def main(argv):
    if argv[:1] == ["list"]:
        for s in SUITE:
            src = s.cs184 and f"../shared/scenes/cs184/{s.cs184}" or s.repo and f"scenes/{s.repo}" \
                or f"derived: {s.derive[1]}"
            print(f"{s.name:22} {s.kind:48} {src}" + (" + sky map (-e)" if s.env else "")
                  + (", file camera" if s.file_camera else ""))
        return 0
    if argv[:1] == ["make"] and len(argv) == 2:
        for s in SUITE:
            if s.derive is None and s.env is None:
                continue
            try:
                path, env = resolve(s, os.path.join(ROOT, "..", "shared", "scenes", "cs184"),
                                    [os.path.join(ROOT, "scenes")], argv[1])
                print(path if env is None else f"{path} -e {env}")
            except MissingScene as e:
                print(f"{s.name}: {e}", file=sys.stderr)
        return 0
    print("usage: suite_scenes.py list | make DIR", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
