#!/usr/bin/env python3
"""Writes scenes/many-lights.dae: two storeys of four rooms in a row, each room lit by its own
fifteen point lamps, 120 lights in all, for light-selection
benchmarks.

Usage: tools/make_many_lights.py > scenes/many-lights.dae
The output depends on nothing but this file (a fixed pseudo-random sequence).
"""
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scene_writer import material, vector_source  # noqa: E402

ROOMS = 8
PER_STOREY = 4
WIDTH, HEIGHT, DEPTH = 4.0, 3.0, 4.0  # one room, metres
# Air between neighbouring rooms (metres). Each room is its own mesh, so rooms placed edge to edge
# would put two faces in one plane (a side wall against its neighbour's, a ceiling against the floor
# above). Coplanar faces are ill-posed geometry: a renderer that keeps rays off a surface by skipping
# the primitive they leave (Cycles) then hits the neighbour's face at t ~ 0 and loses shadow and
# bounce rays, while one that offsets the origin (candela) does not, so the two disagree by far more
# than their noise. With the gap every face has a plane of its own.
ROOM_GAP = 0.2
LAMPS_PER_ROOM = 14                   # point lights; each room also has one above its crate
# The file camera looks down -z at the middle of the two storeys, far enough back that the 62 degree
# field spans the row of rooms with a little margin.
CAMERA_Y = (2 * HEIGHT + ROOM_GAP) / 2
CAMERA_Z = 16.0


def polylist_room():
    """Floor, ceiling, back wall and the two side walls of a room, open at +z, normals in."""
    w, h, d = WIDTH / 2, HEIGHT, DEPTH / 2
    quads = [  # corners counter-clockwise seen from inside, inward normal
        ([(-w, 0, -d), (-w, 0, d), (w, 0, d), (w, 0, -d)], (0, 1, 0)),
        ([(-w, h, -d), (w, h, -d), (w, h, d), (-w, h, d)], (0, -1, 0)),
        ([(-w, 0, -d), (w, 0, -d), (w, h, -d), (-w, h, -d)], (0, 0, 1)),
        ([(-w, 0, -d), (-w, h, -d), (-w, h, d), (-w, 0, d)], (1, 0, 0)),
        ([(w, 0, -d), (w, 0, d), (w, h, d), (w, h, -d)], (-1, 0, 0)),
    ]
    pos, nrm, p = [], [], []
    for k, (corners, n) in enumerate(quads):
        for c in corners:
            p += [len(pos), k]
            pos.append(c)
        nrm.append(n)
    return pos, nrm, p, len(quads)


def fmt(vs):
    return "  ".join(" ".join(f"{x:g}" for x in v) for v in vs)


def source(sid, vs):
    """A <source> of 3-vectors, with its line break."""
    return vector_source(sid, fmt(vs), len(vs)) + "\n"


def mesh(name, pos, nrm, p, count, vcount):
    return f"""    <geometry id="{name}" name="{name}">
      <mesh>
{source(f"{name}-positions", pos)}{source(f"{name}-normals", nrm)}        <vertices id="{name}-vertices">
          <input semantic="POSITION" source="#{name}-positions"/>
        </vertices>
        <polylist material="surface" count="{count}">
          <input semantic="VERTEX" source="#{name}-vertices" offset="0"/>
          <input semantic="NORMAL" source="#{name}-normals" offset="1"/>
          <vcount>{" ".join(["4"] * count)}</vcount>
          <p>{" ".join(str(i) for i in p)}</p>
        </polylist>
      </mesh>
    </geometry>
"""


def cube():
    pos = [(x, y, z) for z in (-0.5, 0.5) for y in (-0.5, 0.5) for x in (-0.5, 0.5)]
    faces = [((0, 2, 3, 1), (0, 0, -1)), ((4, 5, 7, 6), (0, 0, 1)), ((0, 1, 5, 4), (0, -1, 0)),
             ((2, 6, 7, 3), (0, 1, 0)), ((0, 4, 6, 2), (-1, 0, 0)), ((1, 3, 7, 5), (1, 0, 0))]
    p, nrm = [], []
    for k, (f, n) in enumerate(faces):
        for i in f:
            p += [i, k]
        nrm.append(n)
    return pos, nrm, p, len(faces)


def effect(name, rgb):
    return f"""    <effect id="{name}-effect">
      <profile_COMMON><technique sid="common"><lambert>
        <diffuse><color sid="diffuse">{rgb[0]:g} {rgb[1]:g} {rgb[2]:g} 1</color></diffuse>
      </lambert></technique></profile_COMMON>
    </effect>
"""


def instance(node, geom, mat, transform):
    return f"""      <node id="{node}" name="{node}" type="NODE">
        {transform}
        <instance_geometry url="#{geom}" name="{node}">
          <bind_material><technique_common>
            <instance_material symbol="surface" target="#{mat}-material"/>
          </technique_common></bind_material>
        </instance_geometry>
      </node>
"""


def point_light(name, rgb):
    """A point lamp of colour `rgb` (inverse-square falloff)."""
    return f"""    <light id="{name}" name="{name}"><technique_common><point>
      <color sid="color">{rgb[0]:.4f} {rgb[1]:.4f} {rgb[2]:.4f}</color>
      <constant_attenuation>0</constant_attenuation><linear_attenuation>0</linear_attenuation>
      <quadratic_attenuation>1</quadratic_attenuation>
    </point></technique_common></light>
"""


def light_node(name, position):
    """The node placing lamp `name` at `position` (its coordinates' text)."""
    return f"""      <node id="{name}-node" name="{name}-node" type="NODE">
        <translate sid="location">{position}</translate>
        <instance_light url="#{name}"/>
      </node>
"""


def many_lights():
    """The scene's COLLADA text (without the final line break)."""
    rng = random.Random(184)
    lights, nodes = [], []
    materials = {"wall": (0.75, 0.74, 0.72), "crate": (0.6, 0.45, 0.3), "slate": (0.3, 0.33, 0.4)}
    for r in range(ROOMS):
        x0 = (r % PER_STOREY - (PER_STOREY - 1) / 2) * (WIDTH + ROOM_GAP)
        y0 = (r // PER_STOREY) * (HEIGHT + ROOM_GAP)
        nodes.append(instance(f"room{r}", "room", "wall",
                              f'<translate sid="location">{x0:g} {y0:g} 0</translate>'))
        cx, cz = x0 + rng.uniform(-0.8, 0.8), rng.uniform(-1.2, 0.4)
        nodes.append(instance(f"crate{r}", "cube", "crate" if r % 2 else "slate",
                              f'<translate sid="location">{cx:.3f} {y0 + 0.4:g} {cz:.3f}'
                              f'</translate><scale sid="scale">0.8 0.8 0.8</scale>'))
        # Rooms differ in brightness by up to 100x; lamps in one room by up to 10x.
        room_scale = 10 ** rng.uniform(-1.0, 1.0)
        for k in range(LAMPS_PER_ROOM):
            name = f"lamp{r}-{k}"
            warm = rng.uniform(0.0, 1.0)
            i = room_scale * 10 ** rng.uniform(-0.5, 0.5) * 0.4
            lights.append(point_light(name, (i, i * (0.8 + 0.15 * warm), i * (0.55 + 0.4 * warm))))
            px = x0 + rng.uniform(-1.7, 1.7)
            py = y0 + rng.uniform(1.6, 2.85)
            pz = rng.uniform(-1.7, 1.5)
            nodes.append(light_node(name, f"{px:.3f} {py:.3f} {pz:.3f}"))
        # A brighter lamp just above the crate.
        name = f"crate-lamp{r}"
        s = 1.5 * room_scale
        lights.append(point_light(name, (s, s, s * 0.9)))
        nodes.append(light_node(name, f"{cx:.3f} {y0 + 1.6:g} {cz:.3f}"))

    room = polylist_room()
    box = cube()
    total = ROOMS * (LAMPS_PER_ROOM + 1)
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!--
  many-lights.dae: two storeys of {PER_STOREY} rooms, open toward the camera, each lit by its own
  {LAMPS_PER_ROOM} point lamps and a brighter one over its crate: {total} lights in all, rooms differing in
  brightness by up to 100x (Y_UP file). Written by tools/make_many_lights.py. A light in one room
  lights nothing in the others, so a choice by power alone wastes most shadow rays.
  Render it with the file camera (camera option "file"): the framed camera stands too far off.
-->
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <contributor><author>candela</author><authoring_tool>tools/make_many_lights.py</authoring_tool></contributor>
    <created>2026-11-27T00:00:00</created>
    <modified>2026-11-27T00:00:00</modified>
    <unit name="meter" meter="1"/>
    <up_axis>Y_UP</up_axis>
  </asset>
  <library_cameras>
    <camera id="main-camera" name="main-camera">
      <optics><technique_common><perspective>
        <xfov sid="xfov">62</xfov><aspect_ratio>1.333333</aspect_ratio>
        <znear sid="znear">0.01</znear><zfar sid="zfar">200</zfar>
      </perspective></technique_common></optics>
    </camera>
  </library_cameras>
  <library_lights>
{"".join(lights)}  </library_lights>
  <library_effects>
{"".join(effect(k, v) for k, v in materials.items())}  </library_effects>
  <library_materials>
{"".join(material(k) for k in materials)}  </library_materials>
  <library_geometries>
{mesh("room", room[0], room[1], room[2], room[3], 4)}{mesh("cube", box[0], box[1], box[2], box[3], 4)}  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="many-lights-scene" name="many-lights-scene">
      <node id="camera-node" name="camera-node" type="NODE">
        <translate sid="location">0 {CAMERA_Y:g} {CAMERA_Z:g}</translate>
        <instance_camera url="#main-camera"/>
      </node>
{"".join(nodes)}    </visual_scene>
  </library_visual_scenes>
  <scene>
    <instance_visual_scene url="#many-lights-scene"/>
  </scene>
</COLLADA>"""


def main():
    print(many_lights())


if __name__ == "__main__":
    main()
