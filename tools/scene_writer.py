#!/usr/bin/env python3
"""COLLADA text of the CS184 scenes the tools write: the one home of it.

Its writers: tools/make_metal_scenes.py (scenes/mirror-coil.dae, scenes/rough-metal.dae),
tools/make_many_lights.py (scenes/many-lights.dae), tools/suite_scenes.py (the performance
suite's derived scenes: the copper bunny, the large mesh) and tools/light_kinds.py.

Two layouts, each kept byte for byte, since files written in them are committed (scenes/) or
cached by their hash (the suite's references, tools/compare_cycles.py):

  * the readable layout, one element a line (the committed metal scenes): vector_source,
    lambert_effect, cgl_effect, microfacet_effect, mirror_effect, mesh_geometry,
    sphere_geometry, instance_node;
  * the compact layout, a few lines an element (the scenes written at run time): effect,
    material, mesh, node, sphere, microfacet, document.

Besides: the vector arithmetic of the generated meshes, the conductors' optical constants,
the number format of the readable layout, and the copper bunny (copper_bunny), derived here
alone.

    python3 tools/scene_writer.py --self-test

checks the pieces, that every writer's scene is well-formed XML, and that the committed scenes
come out of their scripts byte for byte.
"""

import math
import re
import sys

# Conductors' complex index of refraction (eta, k) at the RGB wavelengths of the CS184 scenes.
SILVER = ("0.059193 0.059881 0.047366", "4.1283 3.5892 2.8132")
ALUMINIUM = ("1.3352 1.0109 0.68955", "7.3398 6.6157 5.6471")
COPPER = ("0.33228 1.0162 1.2474", "3.1646 2.5785 2.4603")
# The course's roughness of its copper bunny (CBbunny_microfacet_cu: spec section 10).
COPPER_BUNNY_ALPHA = 0.05


def fixed(x):
    """x with at most six decimals, trailing zeros dropped ("0" for zero and -0)."""
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def g6(x):
    return f"{x:.6g}"


# ---- vectors ----------------------------------------------------------------------------------

def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


# ---- the readable layout ----------------------------------------------------------------------

def vector_source(source_id, text, count):
    """A <source> of `count` 3-vectors whose numbers are `text`, at a mesh's indentation (no
    line break before or after)."""
    return f"""        <source id="{source_id}">
          <float_array id="{source_id}-array" count="{3 * count}">{text}</float_array>
          <technique_common>
            <accessor source="#{source_id}-array" count="{count}" stride="3">
              <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>"""


def lambert_effect(name, rgb, emission=None):
    """A diffuse effect; with `emission` (an RGB string), CGL emission of that radiance."""
    cgl = ""
    if emission is not None:
        cgl = f"""
      <extra>
        <technique profile="CGL">
          <emission>
            <radiance>{emission}</radiance>
          </emission>
        </technique>
      </extra>"""
    return f"""    <effect id="{name}-effect">
      <profile_COMMON>
        <technique sid="common">
          <lambert>
            <diffuse><color sid="diffuse">{rgb} 1</color></diffuse>
          </lambert>
        </technique>
      </profile_COMMON>{cgl}
    </effect>
"""


def cgl_effect(name, body):
    """An effect whose CGL technique holds `body` (a grey phong for readers without CGL)."""
    return f"""    <effect id="{name}-effect">
      <profile_COMMON>
        <technique sid="common">
          <phong>
            <diffuse><color sid="diffuse">0.8 0.8 0.8 1</color></diffuse>
          </phong>
        </technique>
      </profile_COMMON>
      <extra>
        <technique profile="CGL">
{body}
        </technique>
      </extra>
    </effect>
"""


def microfacet_effect(name, metal, alpha):
    eta, k = metal
    return cgl_effect(name, f"""          <microfacet>
            <alpha>{fixed(alpha)}</alpha>
            <eta>{eta}</eta>
            <k>{k}</k>
          </microfacet>""")


def mirror_effect(name, reflectance):
    r = fixed(reflectance)
    return cgl_effect(name, f"""          <mirror>
            <reflectance>{r} {r} {r}</reflectance>
          </mirror>""")


def mesh_geometry(name, positions, tris, material, normal=None):
    """A <triangles> mesh; with `normal`, one NORMAL shared by every corner."""
    if normal is None:
        p = " ".join(str(i) for t in tris for i in t)
        normal_source = normal_input = ""
    else:
        p = " ".join(f"{i} 0" for t in tris for i in t)
        normal_source = "\n" + vector_source(f"{name}-normals", " ".join(
            fixed(c) for c in normal), len(normal) // 3)
        normal_input = f"""
          <input semantic="NORMAL" source="#{name}-normals" offset="1"/>"""
    positions_source = "\n" + vector_source(
        f"{name}-positions", " ".join(fixed(c) for q in positions for c in q), len(positions))
    return f"""    <geometry id="{name}-mesh" name="{name}">
      <mesh>{positions_source}{normal_source}
        <vertices id="{name}-vertices">
          <input semantic="POSITION" source="#{name}-positions"/>
        </vertices>
        <triangles material="{material}" count="{len(tris)}">
          <input semantic="VERTEX" source="#{name}-vertices" offset="0"/>{normal_input}
          <p>{p}</p>
        </triangles>
      </mesh>
    </geometry>
"""


def sphere_geometry(radius):
    """The CGL sphere geometry "sphere-geometry" (instances place it)."""
    return f"""    <geometry id="sphere-geometry" name="sphere">
      <extra>
        <technique profile="CGL">
          <sphere>
            <radius>{fixed(radius)}</radius>
          </sphere>
        </technique>
      </extra>
    </geometry>
"""


def instance_node(name, geometry, material, transform=""):
    """A node instancing `geometry` with `material`; `transform` is its transform elements' text
    (starting with a line break)."""
    return f"""      <node id="{name}" name="{name}" type="NODE">{transform}
        <instance_geometry url="#{geometry}">
          <bind_material>
            <technique_common>
              <instance_material symbol="{material}" target="#{material}"/>
            </technique_common>
          </bind_material>
        </instance_geometry>
      </node>
"""


# ---- the compact layout -----------------------------------------------------------------------

def effect(name, diffuse, cgl=None):
    """A diffuse effect ("NAME-effect") of albedo `diffuse` (an RGB string), with `cgl` as its
    CGL technique's content when given."""
    extra = f'<extra><technique profile="CGL">{cgl}</technique></extra>' if cgl else ""
    return (f'    <effect id="{name}-effect"><profile_COMMON><technique sid="common"><lambert>'
            f'<diffuse><color sid="diffuse">{diffuse} 1</color></diffuse></lambert></technique>'
            f'</profile_COMMON>{extra}</effect>\n')


def microfacet(metal, alpha):
    """A CGL microfacet conductor's element: `metal` is (eta, k), alpha its roughness."""
    eta, k = metal
    return f"<microfacet><alpha>{fixed(alpha)}</alpha><eta>{eta}</eta><k>{k}</k></microfacet>"


def material(name, named=True):
    """Material "NAME-material" of effect "NAME-effect" (with a name attribute when `named`)."""
    attr = f' name="{name}"' if named else ""
    return (f'    <material id="{name}-material"{attr}>'
            f'<instance_effect url="#{name}-effect"/></material>\n')


def mesh(name, verts, tris, symbol, p_on_own_line=False):
    """Geometry "NAME-mesh": triangles (index triples) over verts (xyz), bound to material
    symbol `symbol`."""
    pos = " ".join(g6(x) for v in verts for x in v)
    idx = " ".join(str(i) for t in tris for i in t)
    p_break = "\n        " if p_on_own_line else ""
    return (f'    <geometry id="{name}-mesh" name="{name}"><mesh>\n'
            f'      <source id="{name}-pos"><float_array id="{name}-pos-array" '
            f'count="{3 * len(verts)}">{pos}</float_array>\n'
            f'        <technique_common><accessor source="#{name}-pos-array" count="{len(verts)}" '
            f'stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
            f'<param name="Z" type="float"/></accessor></technique_common></source>\n'
            f'      <vertices id="{name}-vtx"><input semantic="POSITION" source="#{name}-pos"/>'
            f'</vertices>\n'
            f'      <triangles material="{symbol}" count="{len(tris)}">'
            f'<input semantic="VERTEX" source="#{name}-vtx" offset="0"/>{p_break}'
            f'<p>{idx}</p></triangles>\n'
            f'    </mesh></geometry>\n')


def sphere(name, radius):
    """CGL sphere geometry "NAME-sphere"."""
    return (f'    <geometry id="{name}-sphere" name="{name}"><extra><technique profile="CGL">'
            f'<sphere><radius>{g6(radius)}</radius></sphere></technique></extra></geometry>\n')


def node(name, geometry, symbol, material_name, transform=""):
    """A node instancing geometry `geometry`, its material symbol `symbol` bound to
    "MATERIAL_NAME-material"; `transform` is its transform elements' text."""
    return (f'      <node id="{name}" name="{name}">{transform}<instance_geometry '
            f'url="#{geometry}"><bind_material><technique_common><instance_material '
            f'symbol="{symbol}" target="#{material_name}-material"/></technique_common>'
            f'</bind_material></instance_geometry></node>\n')


def document(comment, up_axis, xfov, znear, lights, effects, materials, geometries, nodes):
    """A whole scene in the compact layout: `comment` (the lines inside <!-- -->), the file's
    up axis, one camera "camera" (xfov degrees, 4:3, near plane znear), then each library's
    text and the visual scene's nodes (the camera's node among them)."""
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- {comment} -->
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>{up_axis}</up_axis></asset>
  <library_cameras>
    <camera id="camera" name="camera"><optics><technique_common><perspective>
      <xfov sid="xfov">{xfov}</xfov><aspect_ratio>1.333333</aspect_ratio>
      <znear sid="znear">{znear}</znear><zfar sid="zfar">100</zfar>
    </perspective></technique_common></optics></camera>
  </library_cameras>
  <library_lights>
{lights}  </library_lights>
  <library_effects>
{effects}  </library_effects>
  <library_materials>
{materials}  </library_materials>
  <library_geometries>
{geometries}  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
{nodes}    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


# ---- the copper bunny -------------------------------------------------------------------------

def copper_bunny(text):
    """CBbunny.dae's text with the bunny (node "Mesh") bound to a new microfacet copper
    material ("copper", the course's copper at COPPER_BUNNY_ALPHA) instead of the default
    diffuse one. Raises ValueError when the file does not have the layout this expects (each
    edit must apply exactly once)."""
    copper_effect = ('    <effect id="copper-effect">\n'
                     '      <profile_COMMON><technique sid="common"><phong><diffuse>'
                     '<color sid="diffuse">0.8 0.4 0.3 1</color></diffuse></phong></technique>'
                     '</profile_COMMON>\n'
                     '      <extra><technique profile="CGL">'
                     f'{microfacet(COPPER, COPPER_BUNNY_ALPHA)}</technique></extra>\n'
                     '    </effect>\n')
    edits = [
        (r"(?=  </library_effects>)", copper_effect),
        (r"(?=  </library_materials>)", material("copper")),
        (r'(<node id="Mesh"[^>]*>(?:(?!</node>).)*?<instance_material symbol="Default-material" '
         r'target=")#Default-material(")', r"\1#copper-material\2"),
    ]
    for pattern, repl in edits:
        text, n = re.subn(pattern, repl, text, count=0, flags=re.S)
        if n != 1:
            raise ValueError(f"CBbunny.dae: expected one match of {pattern!r}, found {n}")
    return text


# ---- self-test --------------------------------------------------------------------------------

def self_test():
    import os
    import tempfile
    import xml.etree.ElementTree as ET

    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    import light_kinds
    import make_many_lights
    import make_metal_scenes
    import suite_scenes

    assert fixed(0.5) == "0.5" and fixed(-0.0000001) == "0" and fixed(2.0) == "2"
    assert fixed(1 / 3) == "0.333333" and g6(1 / 3) == "0.333333" and g6(1e-7) == "1e-07"
    assert cross((1, 0, 0), (0, 1, 0)) == (0, 0, 1) and dot((1, 2, 3), (4, 5, 6)) == 32
    assert normalize((0, 3, 4)) == (0, 0.6, 0.8) and sub((1, 2, 3), (1, 1, 1)) == (0, 1, 2)
    # The compact pieces: one triangle, its material, effect and node, parsed as XML.
    tri = mesh("t", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)], "m")
    g = ET.fromstring(tri)
    assert g.find("mesh/triangles").get("count") == "1"
    assert g.find("mesh/triangles/p").text == "0 1 2"
    assert g.find("mesh/source/float_array").text == "0 0 0 1 0 0 0 1 0"
    assert ET.fromstring(mesh("t", [(0, 0, 0)], [], "m", p_on_own_line=True)).find(
        "mesh/triangles/p") is not None
    assert ET.fromstring(material("x")).get("name") == "x"
    assert ET.fromstring(material("x", named=False)).get("name") is None
    e = ET.fromstring(effect("c", "1 0.5 0", microfacet(COPPER, 0.3)))
    assert e.find("extra/technique/microfacet/alpha").text == "0.3"
    assert e.find("extra/technique/microfacet/eta").text == COPPER[0]
    n = ET.fromstring(node("a", "a-mesh", "m", "c", "<translate>1 2 3</translate>"))
    assert n.find("translate").text == "1 2 3"
    assert n.find("instance_geometry/bind_material/technique_common/instance_material").get(
        "target") == "#c-material"
    # The readable pieces: a quad with one normal, and a mirror.
    q = ET.fromstring(mesh_geometry("q", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)],
                                    [(0, 1, 2), (0, 2, 3)], "w-material", (0, 0, 1)))
    assert q.find("mesh/triangles/p").text == "0 0 1 0 2 0 0 0 2 0 3 0"
    assert [s.get("id") for s in q.findall("mesh/source")] == ["q-positions", "q-normals"]
    m = ET.fromstring(mirror_effect("m", 0.9))
    assert m.find("extra/technique/mirror/reflectance").text == "0.9 0.9 0.9"
    # The copper swap edits the bunny's binding and nothing else.
    dae = ('<library_effects>\n  </library_effects>\n<library_materials>\n'
           '  </library_materials>\n<node id="Mesh" name="Mesh"><instance_material '
           'symbol="Default-material" target="#Default-material"/></node>\n<node id="wall">'
           '<instance_material symbol="Default-material" target="#Default-material"/></node>')
    out = copper_bunny(dae)
    assert out.count('target="#copper-material"') == 1 and "<microfacet>" in out
    assert out.count('target="#Default-material"') == 1
    assert f"<alpha>{fixed(COPPER_BUNNY_ALPHA)}</alpha>" in out
    try:
        copper_bunny(dae.replace('id="Mesh"', 'id="Other"'))
        raise AssertionError("a file without the bunny node must be refused")
    except ValueError:
        pass
    # Every writer's scene is well-formed COLLADA.
    ns = "{http://www.collada.org/2005/11/COLLADASchema}"
    for name, text in [("large-mesh", suite_scenes.large_mesh()),
                       ("light-kinds", light_kinds.light_kinds()),
                       ("light-kinds point", light_kinds.light_kinds(["point"], False)),
                       ("many-lights", make_many_lights.many_lights()),
                       ("mirror-coil", make_metal_scenes.mirror_coil()),
                       ("rough-metal", make_metal_scenes.rough_metal())]:
        root = ET.fromstring(text.encode("utf-8"))
        assert root.find(f"{ns}library_visual_scenes") is not None, name
    # The committed scenes come out of their scripts byte for byte.
    root = os.path.dirname(here)
    with tempfile.TemporaryDirectory() as tmp:
        make_metal_scenes.main([tmp])
        written = {f: os.path.join(tmp, f) for f in ("mirror-coil.dae", "rough-metal.dae")}
        written["many-lights.dae"] = os.path.join(tmp, "many-lights.dae")
        with open(written["many-lights.dae"], "w", newline="\n") as f:
            f.write(make_many_lights.many_lights() + "\n")
        for f, path in written.items():
            with open(path, "rb") as a, open(os.path.join(root, "scenes", f), "rb") as b:
                assert a.read() == b.read(), f"scenes/{f} is not what its script writes"
    print("scene_writer self-test: ok")
    return 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    print(__doc__.strip(), file=sys.stderr)
    sys.exit(2)
