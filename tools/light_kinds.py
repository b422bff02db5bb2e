#!/usr/bin/env python3
"""Writes a scene lit by every kind of finite light candela has, in awkward places: the
light-kinds scene of the comparison suite (tools/suite_scenes.py), and its parts one kind at a
time, to compare candela with Cycles kind by kind.

A diffuse floor (y = 0) and back wall (z = -3), a short free-standing wall (one quad, both sides
seen), a rough silver sphere (Beckmann alpha 0.15) and a rough glass sphere (alpha 0.1), lit by

  rect     96 CGL <area> rectangles of 0.01-6 m and radiance 0.01-100 in random orientations
           (many facing away from everything);
  panels   a rectangle lying in the floor's plane facing up, one in the back wall's plane, one
           in the floor's plane facing down (into the floor), and a dim 6 x 6 m panel, tilted, whose
           bounding box holds many of the other lights;
  point    52 point lights, four below the floor, one exactly in the floor's plane and one
           behind the short wall;
  sphere   20 emissive spheres of radius 0.005-0.2 m and radiance 0.1-1000;
  tetra    5 emissive tetrahedra (two-sided emission).

Usage: tools/light_kinds.py [--kinds rect,panels,point,sphere,tetra] [--no-spheres] > scene.dae
The output depends on nothing but this file and the options (a fixed pseudo-random sequence per
kind, so leaving a kind out does not move the others). Render it with the file camera (candela
--camera file, the Cycles peer script --camera collada).
"""

import argparse
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scene_writer  # noqa: E402  (COLLADA text)
from scene_writer import SILVER, cross, normalize  # noqa: E402

KINDS = ("rect", "panels", "point", "sphere", "tetra")

# The room: floor and back wall extents (metres).
FLOOR_X, FLOOR_Z0, FLOOR_Z1 = 6.0, -3.0, 6.0
WALL_Z, WALL_H = -3.0, 4.0
# Region the random lights are placed in (x, y, z ranges).
REGION = ((-5.0, 5.0), (0.05, 3.8), (-2.9, 3.5))
# The short wall (x = SHORT_X, z in SHORT_Z, y in [0, SHORT_H]) hides a point light behind it.
SHORT_X, SHORT_Z, SHORT_H = 3.0, (-1.5, 0.5), 1.5


def log_uniform(rng, lo, hi):
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def random_rotation(rng):
    """A uniformly random rotation matrix (rows), from a random unit quaternion."""
    u1, u2, u3 = rng.random(), rng.random(), rng.random()
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    w, x = a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2)
    y, z = b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3)
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def rect_matrix(centre, rot, sx, sy):
    """Node matrix of a CGL area light: local X scaled by sx, Y by sy, then rotated (rot's
    columns are the local axes in the world) and moved to centre. The light emits along local
    -Z, i.e. along -(rot's third column)."""
    m = [[rot[i][0] * sx, rot[i][1] * sy, rot[i][2], centre[i]] for i in range(3)]
    return " ".join(f"{v:.6g}" for row in m for v in row) + " 0 0 0 1"


def axes_facing(n):
    """A rotation whose third column is -n (so the light emits along n)."""
    z = [-c for c in n]
    t = [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0]
    x = normalize(cross(t, z))
    y = cross(z, x)
    return [[x[i], y[i], z[i]] for i in range(3)]


class Scene:
    def __init__(self):
        self.lights, self.effects, self.geometries, self.nodes = [], [], [], []
        self.materials = []  # the effects' names, each also a material's

    def effect(self, name, body_cgl=None, diffuse="0.8 0.8 0.8"):
        self.materials.append(name)
        self.effects.append(scene_writer.effect(name, diffuse, body_cgl))

    def emission(self, name, radiance):
        self.effect(name, f"<emission><radiance>{radiance:.6g} {radiance:.6g} "
                          f"{radiance:.6g}</radiance></emission>")

    def mesh(self, name, verts, tris):
        self.geometries.append(scene_writer.mesh(name, verts, tris, "m"))

    def instance(self, name, geom, material, transform=""):
        self.nodes.append(scene_writer.node(name, geom, "m", material, transform))

    def sphere(self, name, centre, radius, material):
        self.geometries.append(scene_writer.sphere(name, radius))
        self.instance(name, f"{name}-sphere", material,
                      f'<translate>{centre[0]:.6g} {centre[1]:.6g} {centre[2]:.6g}</translate>')

    def light(self, name, body, transform):
        self.lights.append(f'    <light id="{name}" name="{name}">{body}</light>\n')
        self.nodes.append(f'      <node id="{name}-node" name="{name}-node">{transform}'
                          f'<instance_light url="#{name}"/></node>\n')

    def rect(self, name, centre, rot, sx, sy, radiance):
        self.light(name, f'<extra><technique profile="CGL"><area><color sid="color">'
                         f'{radiance:.6g} {radiance:.6g} {radiance:.6g}</color></area>'
                         f'</technique></extra>',
                   f'<matrix>{rect_matrix(centre, rot, sx, sy)}</matrix>')

    def point(self, name, pos, intensity):
        self.light(name, f'<technique_common><point><color sid="color">{intensity:.6g} '
                         f'{intensity:.6g} {intensity:.6g}</color>'
                         f'<constant_attenuation>0</constant_attenuation>'
                         f'<linear_attenuation>0</linear_attenuation>'
                         f'<quadratic_attenuation>1</quadratic_attenuation></point>'
                         f'</technique_common>',
                   f'<translate>{pos[0]:.6g} {pos[1]:.6g} {pos[2]:.6g}</translate>')


def random_point(rng):
    return [rng.uniform(*r) for r in REGION]


def grid_without_holes(u_range, v_range, holes):
    """Cells (u0, u1, v0, v1) that tile the rectangle u_range x v_range except the holes (each
    (u0, u1, v0, v1), inside the rectangle): the grid of every hole's edges, holes left out."""
    us = sorted({u_range[0], u_range[1], *[h[0] for h in holes], *[h[1] for h in holes]})
    vs = sorted({v_range[0], v_range[1], *[h[2] for h in holes], *[h[3] for h in holes]})
    cells = []
    for u0, u1 in zip(us, us[1:]):
        for v0, v1 in zip(vs, vs[1:]):
            if not any(h[0] <= u0 and u1 <= h[1] and h[2] <= v0 and v1 <= h[3] for h in holes):
                cells.append((u0, u1, v0, v1))
    return cells


def plane_mesh(s, name, cells, corner, flip=False):
    """A mesh of the cells, each two triangles; corner(u, v) is the 3-D point of (u, v). The
    winding faces along (u axis) x (v axis), or against it with `flip`."""
    verts, tris = [], []
    for u0, u1, v0, v1 in cells:
        k = len(verts)
        verts += [corner(u0, v0), corner(u1, v0), corner(u1, v1), corner(u0, v1)]
        tris += [(k, k + 2, k + 1), (k, k + 3, k + 2)] if flip else [(k, k + 1, k + 2),
                                                                   (k, k + 2, k + 3)]
    s.mesh(name, verts, tris)


def add_room(s, spheres, panels):
    """Floor, back wall, short wall and (with `spheres`) the two spheres. With `panels`, the
    floor and the back wall have holes exactly where the panels lying in their planes are, so
    that no point of them coincides with a point of an emitter: where two surfaces overlap in
    one plane, which of them a ray meets is decided by rounding (each renderer in its own way)."""
    s.effect("floor", diffuse="0.6 0.6 0.6")
    s.effect("wall", diffuse="0.5 0.55 0.6")
    s.effect("short", diffuse="0.7 0.6 0.5")
    floor_holes = [PANEL_HOLES[k] for k in ("floor-panel", "under-panel")] if panels else []
    wall_holes = [PANEL_HOLES["wall-panel"]] if panels else []
    plane_mesh(s, "floor", grid_without_holes((-FLOOR_X, FLOOR_X), (FLOOR_Z0, FLOOR_Z1),
                                              floor_holes), lambda x, z: (x, 0, z), flip=True)
    plane_mesh(s, "wall", grid_without_holes((-FLOOR_X, FLOOR_X), (0, WALL_H), wall_holes),
               lambda x, y: (x, y, WALL_Z))
    s.mesh("short", [(SHORT_X, 0, SHORT_Z[0]), (SHORT_X, 0, SHORT_Z[1]),
                     (SHORT_X, SHORT_H, SHORT_Z[1]), (SHORT_X, SHORT_H, SHORT_Z[0])],
           [(0, 1, 2), (0, 2, 3)])
    for n in ("floor", "wall", "short"):
        s.instance(n, f"{n}-mesh", n)
    if spheres:
        s.effect("silver", scene_writer.microfacet(SILVER, 0.15))
        s.effect("rough-glass", "<glass><transmittance>1 1 1</transmittance><reflectance>1 1 1"
                                "</reflectance><roughness>0.1</roughness><ior>1.5</ior></glass>")
        s.sphere("silver-ball", (-1.3, 0.5, 0.8), 0.5, "silver")
        s.sphere("glass-ball", (1.2, 0.5, 0.8), 0.5, "rough-glass")


def add_rects(s):
    rng = random.Random(4001)
    for k in range(96):
        centre = random_point(rng)
        # Mostly small, a few large: sizes log-uniform over 0.01-6 m, capped per axis at 6.
        sx = log_uniform(rng, 0.01, 6.0 if k % 12 == 0 else 1.2)
        sy = sx * rng.uniform(0.3, 1.0)
        s.rect(f"rect{k}", centre, random_rotation(rng), sx, sy, log_uniform(rng, 0.01, 100.0)
               / (1 + sx * sy))


# The panels lying in the floor's and the back wall's planes: (centre, emitting direction,
# extent along the first in-plane axis, along the second, radiance), and the hole each leaves
# in its surface, (u0, u1, v0, v1) in the surface's own coordinates (floor: x, z; wall: x, y).
# axes_facing() puts the local X axis (sx) along z for the floor panels and along y for the
# wall panel, and the local Y axis (sy) along x.
PANELS = {
    # Facing up, seen by the camera; it lights nothing of the floor (every floor point lies in
    # its plane: cos = 0).
    "floor-panel": ((-2.5, 0.0, 2.0), (0, 1, 0), 0.8, 0.5, 3.0),
    # Facing down, into the floor's plane: it lights nothing; the camera sees its dark back.
    "under-panel": ((2.5, 0.0, 2.5), (0, -1, 0), 0.6, 0.6, 5.0),
    # In the back wall's plane, facing the room.
    "wall-panel": ((-3.5, 2.0, WALL_Z), (0, 0, 1), 1.0, 0.6, 4.0),
}
PANEL_HOLES = {
    "floor-panel": (-2.75, -2.25, 1.6, 2.4),
    "under-panel": (2.2, 2.8, 2.2, 2.8),
    "wall-panel": (-3.8, -3.2, 1.5, 2.5),
}


def add_panels(s):
    for name, (centre, n, sx, sy, radiance) in PANELS.items():
        s.rect(name, centre, axes_facing(n), sx, sy, radiance)
    # A dim 6 x 6 m panel under the ceiling, tilted 20 degrees about x, facing down: its bounding
    # box holds the upper third of the other lights. It stands above the camera's view.
    t = math.radians(20.0)
    s.rect("big-panel", (0.0, 3.9, 0.5), axes_facing((0, -math.cos(t), math.sin(t))), 6.0, 6.0,
           0.05)


def add_points(s):
    rng = random.Random(4002)
    for k in range(46):
        s.point(f"point{k}", random_point(rng), log_uniform(rng, 0.01, 3.0))
    for k in range(4):  # below the floor
        s.point(f"below{k}", (rng.uniform(-4, 4), -rng.uniform(0.05, 1.0), rng.uniform(-2, 3)),
                log_uniform(rng, 0.5, 5.0))
    s.point("in-floor", (-1.0, 0.0, 3.0), 2.0)
    s.point("behind-short-wall", (SHORT_X + 0.3, 0.8, -0.5), 2.0)


def add_emissive_spheres(s):
    rng = random.Random(4003)
    for k in range(20):
        radius = log_uniform(rng, 0.005, 0.2)
        s.emission(f"sphere-light{k}", log_uniform(rng, 0.1, 1000.0) * min(1.0, 0.02 / radius))
        c = random_point(rng)
        c[1] = max(c[1], radius + 0.01)
        s.sphere(f"sphere-light{k}", c, radius, f"sphere-light{k}")


def add_tetrahedra(s):
    rng = random.Random(4004)
    for k in range(5):
        size = rng.uniform(0.1, 0.5)
        c = random_point(rng)
        c[1] = max(c[1], size)
        rot = random_rotation(rng)
        base = [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]
        verts = [tuple(c[i] + size / math.sqrt(3) * sum(rot[i][j] * b[j] for j in range(3))
                       for i in range(3)) for b in base]
        s.emission(f"tetra{k}", log_uniform(rng, 0.5, 20.0))
        s.mesh(f"tetra{k}", verts, [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)])
        s.instance(f"tetra{k}", f"tetra{k}-mesh", f"tetra{k}")


def light_kinds(kinds=KINDS, spheres=True):
    """COLLADA text of the scene with the lights of `kinds` (a subset of KINDS) and, when
    `spheres`, the rough silver and rough glass spheres."""
    s = Scene()
    add_room(s, spheres, "panels" in kinds)
    adders = {"rect": add_rects, "panels": add_panels, "point": add_points,
              "sphere": add_emissive_spheres, "tetra": add_tetrahedra}
    for k in kinds:
        adders[k](s)
    materials = "".join(scene_writer.material(m, named=False) for m in s.materials)
    comment = (f'light-kinds.dae: written by tools/light_kinds.py (do not edit); lights: '
               f'{",".join(kinds)}\n     {"with" if spheres else "without"} the silver and '
               'glass spheres. Render with the file camera.')
    camera = ('      <node id="camera-node" name="camera-node"><translate>0 2.2 7.5</translate>\n'
              '        <rotate>1 0 0 -12</rotate><instance_camera url="#camera"/></node>\n')
    return scene_writer.document(comment, "Y_UP", 60, 0.05, "".join(s.lights),
                                 "".join(s.effects), materials, "".join(s.geometries),
                                 camera + "".join(s.nodes))


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--kinds", default=",".join(KINDS),
                   help=f"comma-separated subset of {','.join(KINDS)}")
    p.add_argument("--no-spheres", action="store_true",
                   help="leave out the silver and glass spheres")
    a = p.parse_args(argv)
    kinds = [k for k in a.kinds.split(",") if k]
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        p.error(f"unknown kind(s) {', '.join(bad)} (kinds: {', '.join(KINDS)})")
    sys.stdout.write(light_kinds(kinds, not a.no_spheres))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
