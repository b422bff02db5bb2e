#!/usr/bin/env python3
"""Writes scenes/mirror-coil.dae and scenes/rough-metal.dae (CS184 COLLADA, Z_UP).

Both scenes put their objects in the Cornell box of scenes/cornell-spheres.dae (2 m wide,
1.6 m high, open toward the camera, a 0.6 m x 0.5 m CGL <area> light of radiance 15 under the
ceiling with its emissive stand-in panel in the same plane):

  * mirror-coil.dae: a helix tube (4 turns) with end caps, a closed mesh written without a
    NORMAL input, so readers compute area-weighted smooth vertex normals (candela and
    render_cycles.py compute the same ones), bound to a CGL <mirror>. It fills about a third of
    the framed view, and the walls are lit partly through reflections off it;
  * rough-metal.dae: four CGL spheres of Beckmann microfacet conductors (silver alpha 0.05,
    aluminium 0.15, copper 0.3, silver 0.5) and a smooth-shaded copper torus mesh (alpha 0.15,
    no NORMAL input) on the floor.

The output is deterministic: run `python3 tools/make_metal_scenes.py` from the repository root
to regenerate both files byte for byte.
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scene_writer import (ALUMINIUM, COPPER, SILVER, cross, dot, fixed,  # noqa: E402
                          instance_node, lambert_effect, mesh_geometry, microfacet_effect,
                          mirror_effect, normalize, sphere_geometry, sub)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Coil: helix axis along file z, centred at (COIL_CX, COIL_CY).
COIL_CX, COIL_CY = 0.0, -0.15
COIL_RADIUS = 0.6           # helix radius (m)
COIL_TUBE = 0.1             # tube radius (m)
COIL_Z0, COIL_Z1 = 0.12, 1.32  # centre-line height at the two ends (m)
COIL_TURNS = 4
COIL_SEGMENTS = 72 * COIL_TURNS  # rings along the helix
COIL_SIDES = 20             # vertices per ring
COIL_REFLECTANCE = 0.9

# Torus of rough-metal.dae, lying on the floor.
TORUS_CENTRE = (0.0, -0.45, 0.07)
TORUS_MAJOR, TORUS_MINOR = 0.22, 0.07
TORUS_SEGMENTS, TORUS_SIDES = 32, 12

SPHERE_RADIUS = 0.22
# (name, metal, alpha, file-space centre)
METAL_SPHERES = [
    ("ag-0_05", SILVER, 0.05, (-0.72, 0.25, SPHERE_RADIUS)),
    ("al-0_15", ALUMINIUM, 0.15, (-0.24, 0.25, SPHERE_RADIUS)),
    ("cu-0_3", COPPER, 0.3, (0.24, 0.25, SPHERE_RADIUS)),
    ("ag-0_5", SILVER, 0.5, (0.72, 0.25, SPHERE_RADIUS)),
]
TORUS_METAL, TORUS_ALPHA = COPPER, 0.15


def tube_mesh(rings, closed_loop):
    """Triangles joining consecutive rings (each a list of (centre, vertices)).

    Returns (positions, triangles). Faces are wound so that their normals point away from the
    ring's centre. An open tube gets a fan cap at each end (one centre vertex each), so the
    mesh is closed either way."""
    sides = len(rings[0][1])
    pos = [p for _, ring in rings for p in ring]
    tris = []
    n = len(rings)
    spans = n if closed_loop else n - 1
    for i in range(spans):
        a0, b0 = i * sides, ((i + 1) % n) * sides
        for j in range(sides):
            j1 = (j + 1) % sides
            tris.append((a0 + j, b0 + j, b0 + j1))
            tris.append((a0 + j, b0 + j1, a0 + j1))
    # Orient the side faces outward: test the first face against its ring centre.
    t = tris[0]
    fn = cross(sub(pos[t[1]], pos[t[0]]), sub(pos[t[2]], pos[t[0]]))
    if dot(fn, sub(pos[t[0]], rings[0][0])) < 0:
        tris = [(a, c, b) for a, b, c in tris]
    if not closed_loop:
        for ring_index, away in ((0, -1.0), (n - 1, 1.0)):
            centre = rings[ring_index][0]
            other = rings[ring_index - int(away)][0]
            axis = sub(centre, other)  # points out of the tube at this end
            c = len(pos)
            pos.append(centre)
            base = ring_index * sides
            for j in range(sides):
                f = (c, base + j, base + (j + 1) % sides)
                fn = cross(sub(pos[f[1]], pos[f[0]]), sub(pos[f[2]], pos[f[0]]))
                tris.append(f if dot(fn, axis) > 0 else (f[0], f[2], f[1]))
    return pos, tris


def ring(centre, u, v, radius, sides):
    return [tuple(centre[k] + radius * (math.cos(2 * math.pi * j / sides) * u[k] +
                                        math.sin(2 * math.pi * j / sides) * v[k])
                  for k in range(3)) for j in range(sides)]


def coil_mesh():
    rings = []
    for i in range(COIL_SEGMENTS + 1):
        t = i / COIL_SEGMENTS
        th = 2 * math.pi * COIL_TURNS * t
        c = (COIL_CX + COIL_RADIUS * math.cos(th), COIL_CY + COIL_RADIUS * math.sin(th),
             COIL_Z0 + (COIL_Z1 - COIL_Z0) * t)
        tangent = normalize((-COIL_RADIUS * math.sin(th) * 2 * math.pi * COIL_TURNS,
                             COIL_RADIUS * math.cos(th) * 2 * math.pi * COIL_TURNS,
                             COIL_Z1 - COIL_Z0))
        inward = (-math.cos(th), -math.sin(th), 0.0)  # perpendicular to the tangent
        rings.append((c, ring(c, inward, cross(tangent, inward), COIL_TUBE, COIL_SIDES)))
    return tube_mesh(rings, closed_loop=False)


def torus_mesh():
    rings = []
    cx, cy, cz = TORUS_CENTRE
    for i in range(TORUS_SEGMENTS):
        th = 2 * math.pi * i / TORUS_SEGMENTS
        c = (cx + TORUS_MAJOR * math.cos(th), cy + TORUS_MAJOR * math.sin(th), cz)
        rings.append((c, ring(c, (math.cos(th), math.sin(th), 0.0), (0.0, 0.0, 1.0),
                              TORUS_MINOR, TORUS_SIDES)))
    return tube_mesh(rings, closed_loop=True)


# The box: (name, material, corners in order, inward normal). Wound like cornell-spheres.dae.
BOX_WALLS = [
    ("floor", "grey", [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], (0, 0, 1)),
    ("ceiling", "grey", [(-1, -1, 1.6), (-1, 1, 1.6), (1, 1, 1.6), (1, -1, 1.6)], (0, 0, -1)),
    ("backWall", "grey", [(-1, 1, 0), (1, 1, 0), (1, 1, 1.6), (-1, 1, 1.6)], (0, -1, 0)),
    ("leftWall", "red", [(-1, -1, 0), (-1, 1, 0), (-1, 1, 1.6), (-1, -1, 1.6)], (1, 0, 0)),
    ("rightWall", "blue", [(1, -1, 0), (1, -1, 1.6), (1, 1, 1.6), (1, 1, 0)], (-1, 0, 0)),
    ("lightPanel", "panel", [(-0.3, -0.15, 1.59), (-0.3, 0.35, 1.59), (0.3, 0.35, 1.59),
                             (0.3, -0.15, 1.59)], (0, 0, -1)),
]
BOX_EFFECTS = [("grey", "0.6 0.6 0.6", None), ("red", "0.6 0.15 0.12", None),
               ("blue", "0.15 0.2 0.6", None), ("panel", "0.8 0.8 0.8", "15 15 15")]


def document(header, effects, geometries, nodes):
    """A whole scene: the box, its light and camera, plus the given objects.

    `effects` holds (name, effect text) pairs; each gets a material named name-material."""
    effects = [(n, lambert_effect(n, rgb, em)) for n, rgb, em in BOX_EFFECTS] + effects
    materials = "".join(f"""    <material id="{n}-material" name="{n}">
      <instance_effect url="#{n}-effect"/>
    </material>
""" for n, _ in effects)
    wall_geometries = "".join(
        mesh_geometry(name, corners, [(0, 1, 2), (0, 2, 3)], f"{mat}-material", normal)
        for name, mat, corners, normal in BOX_WALLS)
    wall_nodes = "".join(instance_node(name, f"{name}-mesh", f"{mat}-material")
                         for name, mat, _, _ in BOX_WALLS)
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!--
{header.rstrip()}
  Generated by tools/make_metal_scenes.py (edit the script, not this file).
-->
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <contributor>
      <author>candela</author>
      <authoring_tool>tools/make_metal_scenes.py</authoring_tool>
    </contributor>
    <unit name="meter" meter="1"/>
    <up_axis>Z_UP</up_axis>
  </asset>
  <library_cameras>
    <camera id="camera" name="camera">
      <optics>
        <technique_common>
          <perspective>
            <xfov sid="xfov">45</xfov>
            <aspect_ratio>1.333333</aspect_ratio>
            <znear sid="znear">0.1</znear>
            <zfar sid="zfar">100</zfar>
          </perspective>
        </technique_common>
      </optics>
    </camera>
  </library_cameras>
  <library_lights>
    <light id="ceiling-light" name="ceilingLight">
      <extra>
        <technique profile="CGL">
          <area>
            <color sid="color">15 15 15</color>
          </area>
        </technique>
      </extra>
    </light>
  </library_lights>
  <library_effects>
{"".join(text for _, text in effects)}  </library_effects>
  <library_materials>
{materials}  </library_materials>
  <library_geometries>
{wall_geometries}{"".join(geometries)}  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene" name="Scene">
      <node id="camera-node" name="camera" type="NODE">
        <translate>0 -4.5 0.8</translate>
        <rotate>1 0 0 90</rotate>
        <instance_camera url="#camera"/>
      </node>
      <node id="light-node" name="ceilingLight" type="NODE">
        <translate>0 0.1 1.59</translate>
        <scale>0.6 0.5 1</scale>
        <instance_light url="#ceiling-light"/>
      </node>
{wall_nodes}{"".join(nodes)}    </visual_scene>
  </library_visual_scenes>
  <scene>
    <instance_visual_scene url="#Scene"/>
  </scene>
</COLLADA>
"""


BOX_TEXT = """\
  File coordinates: the box of cornell-spheres.dae (floor z = 0, ceiling z = 1.6, x in [-1, 1]
  with the red wall at x = -1 and the blue wall at x = +1, back wall at y = +1, open at
  y = -1), its 0.6 x 0.5 CGL <area> light of radiance 15 at z = 1.59 with the emissive
  stand-in panel in the same plane, and its camera (file pose at (0, -4.5, 0.8) looking
  along +y, xfov 45; the framed camera orbits from the -z side of the world)."""


def mirror_coil():
    pos, tris = coil_mesh()
    header = f"""\
  mirror-coil.dae: a mirror coil in a Cornell box (Z_UP file).
  Exercises: a closed helix-tube mesh ({COIL_TURNS} turns, helix radius {fixed(COIL_RADIUS)} m, tube
  radius {fixed(COIL_TUBE)} m, {len(tris)} triangles, fan end caps) without a NORMAL input, so its smooth
  vertex normals are computed (area-weighted) and interpolated across the faceted tube; a CGL
  <mirror> of reflectance {fixed(COIL_REFLECTANCE)}. The coil fills about a third of the framed view, and
  the walls are lit partly through reflections off it (caustic paths light-mirror-wall).
{BOX_TEXT}"""
    return document(header, [("coil", mirror_effect("coil", COIL_REFLECTANCE))],
                    [mesh_geometry("coil", pos, tris, "coil-material")],
                    [instance_node("coil", "coil-mesh", "coil-material")])


def rough_metal():
    pos, tris = torus_mesh()
    effects = [(name, microfacet_effect(name, metal, alpha))
               for name, metal, alpha, _ in METAL_SPHERES]
    effects.append(("torus", microfacet_effect("torus", TORUS_METAL, TORUS_ALPHA)))
    nodes = [instance_node(f"sphere-{name}", "sphere-geometry", f"{name}-material",
                           f"\n        <translate>{' '.join(fixed(c) for c in centre)}</translate>")
             for name, _, _, centre in METAL_SPHERES]
    nodes.append(instance_node("torus", "torus-mesh", "torus-material"))
    spheres = "\n".join(f"  * {name}: radius {fixed(SPHERE_RADIUS)} at "
                        f"({', '.join(fixed(c) for c in centre)}), alpha {fixed(alpha)}"
                        for name, _, alpha, centre in METAL_SPHERES)
    header = f"""\
  rough-metal.dae: rough metals of several roughnesses in a Cornell box (Z_UP file).
  Exercises: Beckmann CGL <microfacet> conductors (silver, aluminium and copper eta/k of the
  CS184 scenes) on four CGL spheres sharing one geometry, left to right:
{spheres}
  and a copper torus (alpha {fixed(TORUS_ALPHA)}, {len(tris)} triangles, no NORMAL input, so smooth normals are
  computed and interpolated) lying on the floor in front of them.
{BOX_TEXT}"""
    return document(header, effects,
                    [sphere_geometry(SPHERE_RADIUS), mesh_geometry("torus", pos, tris, "torus-material")], nodes)


def main(argv):
    out = argv[0] if argv else os.path.join(ROOT, "scenes")
    for name, text in (("mirror-coil.dae", mirror_coil()), ("rough-metal.dae", rough_metal())):
        with open(os.path.join(out, name), "w", newline="\n") as f:
            f.write(text)


if __name__ == "__main__":
    main(sys.argv[1:])
