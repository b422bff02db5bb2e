"""Runs the Cycles peer script (render_cycles.py) with the scene's infinite lights as Cycles'
world, which the peer script leaves black: every <ambient> light of the scene (uniform
radiance over the hemisphere around the file's up axis, as candela reads it) and, with
--env-map, a lat-long environment map in candela's (the scene-format spec's) orientation.

Run inside Blender, like the peer script, with two options of its own among the peer script's:

    blender -b --factory-startup --python-exit-code 1 -P tools/cycles_world.py -- \
        --peer-script PATH/render_cycles.py [--env-map sky.exr] --scene ... (peer options)

The peer script's JSON line gains "world": what the world holds (without ambient lights and
--env-map the world stays black). Only Y_UP files take an environment map here: for other up axes
the mapping of the map onto directions would need candela's rotation of the file, so the script
stops with an error rather than render a wrongly oriented sky.

Three more of candela's readings of a scene, where the peer script reads it as the course's
reference or Blender's defaults do:

  * meshes shade with the file's NORMAL data where it has some (per corner, as candela does),
    not with normals recomputed from the faces: a flat-shaded box stays flat;
  * a <matrix> of 12 to 15 numbers (CBgems' camera has 15) keeps its three complete rows and
    takes (0 0 0 1) as the bottom row, where the peer script stops with an error;
  * shadow rays leave a surface from the surface: Cycles' shadow-terminator geometry offset
    (0.1 by default) is set to 0 on every mesh;
  * a point light lying in the plane of a mesh face, over the face, lights both sides of the
    face in full and nothing in its plane: it becomes two 180-degree spot lamps, one per side,
    a hair off the plane (split_in_plane_point_lights). Cycles' shadow rays toward the lamp
    itself end on the face, and rounding made the face block most of them.

It also warns (in the JSON line's warnings) about CGL spheres under a transform that is not a
similarity: candela renders the ellipsoid, the peer script a sphere.
"""

import importlib.util
import sys

# Resolution of Cycles' world importance map for ambient light alone (two constant halves).
AMBIENT_MAP_RESOLUTION = 64


def split_args(argv):
    """(peer script path, env map or None, the argv the peer script should see)."""
    if "--" not in argv:
        raise SystemExit("cycles_world.py: options go after --")
    head, rest = argv[:argv.index("--") + 1], argv[argv.index("--") + 1:]
    peer, env, keep = None, None, []
    i = 0
    while i < len(rest):
        if rest[i] in ("--peer-script", "--env-map") and i + 1 < len(rest):
            if rest[i] == "--peer-script":
                peer = rest[i + 1]
            else:
                env = rest[i + 1]
            i += 2
        else:
            keep.append(rest[i])
            i += 1
    if peer is None:
        raise SystemExit("cycles_world.py: --peer-script PATH is required")
    return peer, env, head + keep


# Relative tolerance on M^T M = s^2 I: a sphere's transform within it is a similarity, which the
# peer script renders right (it keeps only the centre and |M x| as the radius).
SIMILARITY_TOLERANCE = 1e-4


def note_ellipsoids(peer, dae):
    """Warns (into the JSON line's warnings) about CGL spheres under a transform that is not a
    similarity: candela renders the ellipsoid such a transform describes, the peer script a
    sphere."""
    from mathutils import Matrix

    def walk(node, parent):
        m = parent @ peer.Dae._local_matrix(node)
        for ig in node.findall("instance_geometry"):
            geom = dae.ref(ig.get("url"))
            if geom is None or geom.find("mesh") is not None or peer.find_cgl(geom) is None:
                continue
            a = m.to_3x3()
            g = a.transposed() @ a
            s2 = (g[0][0] + g[1][1] + g[2][2]) / 3
            if any(abs(g[i][j] - (s2 if i == j else 0.0)) > SIMILARITY_TOLERANCE * s2
                   for i in range(3) for j in range(3)):
                dae.warn(f"node {node.get('name') or node.get('id')}: a sphere under a "
                         "non-uniform transform (an ellipsoid) is rendered as a sphere")
        for child in node.findall("node"):
            walk(child, m)

    vs = dae.root.find("library_visual_scenes/visual_scene")
    if vs is not None:
        for node in vs.findall("node"):
            walk(node, Matrix.Identity(4))


# Matrices that were short of numbers, as the peer script's parser met them (reported as
# warnings once the scene is parsed: the parser has no scene to warn through).
SHORT_MATRICES = []


def pad_short_matrices(peer):
    """Makes the peer script's transform parser read a <matrix> of 12-15 numbers as candela
    does: its three complete rows over a (0 0 0 1) bottom row."""
    local_matrix = peer.Dae._local_matrix

    def padded(node):
        for e in node:
            if e.tag != "matrix":
                continue
            v = peer.floats(e.text)
            if 12 <= len(v) < 16:
                SHORT_MATRICES.append(f"node {node.get('name') or node.get('id')}: <matrix> of "
                                      f"{len(v)} numbers, bottom row taken as (0 0 0 1)")
                e.text = " ".join(repr(x) for x in v[:12]) + " 0 0 0 1"
        return local_matrix(node)

    peer.Dae._local_matrix = staticmethod(padded)


# Per-corner file normals of each parsed mesh group, keyed by the id() of the group's polygon
# list, which the peer script hands unchanged to add_mesh_object (the scene object keeps the
# lists alive for the whole run).
FILE_NORMALS = {}


def mesh_sources(peer, mesh):
    """The float arrays of a <mesh> by source id, with their accessor strides."""
    sources = {}
    for src in mesh.findall("source"):
        fa = src.find("float_array")
        acc = src.find("technique_common/accessor")
        if fa is not None:
            sources[src.get("id")] = (peer.floats(fa.text),
                                      int(acc.get("stride", "3")) if acc is not None else 3)
    return sources


def corner_normals(peer, mesh, sources, prim, m):
    """The world-space normal of every corner of `prim` in the order of its polygons' vertex
    indices, from its NORMAL input or the <vertices> one; None when it has neither. `sources`:
    mesh_sources() of `mesh`."""
    inputs = prim.findall("input")
    stride = max(int(i.get("offset", "0")) for i in inputs) + 1
    voff = next((int(i.get("offset", "0")) for i in inputs if i.get("semantic") == "VERTEX"), 0)
    per_corner = next((i for i in inputs if i.get("semantic") == "NORMAL"), None)
    per_vertex = None
    vtx = mesh.find("vertices")
    if vtx is not None:
        per_vertex = next((i for i in vtx.findall("input") if i.get("semantic") == "NORMAL"),
                          None)
    use = per_corner if per_corner is not None else per_vertex
    if use is None:
        return None
    data, nstride = sources[use.get("source", "")[1:]]
    offset = int(use.get("offset", "0")) if use is per_corner else voff
    # Normals transform by the inverse transpose of the node's linear part.
    nm = m.to_3x3().inverted_safe().transposed()
    from mathutils import Vector
    if prim.tag == "polygons":
        index_lists = [peer.ints(p.text) for p in prim.findall("p")]
    else:
        index_lists = [peer.ints(prim.findtext("p"))]
    out = []
    for idx in index_lists:
        for k in range(offset, len(idx), stride):
            j = idx[k] * nstride
            n = nm @ Vector(data[j:j + 3])
            out.append(n.normalized() if n.length > 0 else n)
    return out


def facing(verts, poly):
    """A polygon's winding normal (Newell's sum; its length is twice the area)."""
    from mathutils import Vector
    n = Vector((0.0, 0.0, 0.0))
    for a, b in zip(poly, poly[1:] + poly[:1]):
        n += verts[a].cross(verts[b])
    return n


def keep_file_normals(peer):
    """Records the file normals of every mesh group the peer script parses, and gives them to
    the Blender meshes it builds as custom split normals (per corner)."""
    parse_mesh = peer.Dae._parse_mesh

    def parse_with_normals(self, geom, m, name, bind, first):
        before = len(self.meshes)
        parse_mesh(self, geom, m, name, bind, first)
        mesh = geom.find("mesh")
        prims = [p for p in mesh if p.tag in ("polylist", "triangles", "polygons")
                 and p.findall("input")]
        added = self.meshes[before:]
        if len(added) != len(prims):
            raise peer.DaeError(f"{self.path}: geometry {geom.get('id')}: {len(prims)} "
                                f"primitive lists but {len(added)} parsed groups")
        sources = mesh_sources(peer, mesh)
        for me, prim in zip(added, prims):
            normals = corner_normals(peer, mesh, sources, prim, m)
            corners = sum(len(p) for p in me["polys"])
            if normals is None:
                continue
            if len(normals) != corners:
                raise peer.DaeError(f"{self.path}: geometry {geom.get('id')}: {len(normals)} "
                                    f"normals for {corners} corners")
            FILE_NORMALS[id(me["polys"])] = normals

    peer.Dae._parse_mesh = parse_with_normals
    add_mesh_object = peer.add_mesh_object

    def add_with_file_normals(name, verts, polys, mat, custom_normals=None):
        normals = FILE_NORMALS.get(id(polys))
        if normals is None:
            return add_mesh_object(name, verts, polys, mat, custom_normals)
        # candela takes the side the file's normals point to as a surface's front (a
        # dielectric's outside; an opaque surface shades on the side it is seen from), Cycles
        # the side its winding faces: a polygon whose winding faces away from its normals is
        # turned over, so that Cycles' geometric and shading normals agree as candela's do.
        turned, turned_normals, k = [], [], 0
        for p in polys:
            ns = normals[k:k + len(p)]
            k += len(p)
            if facing(verts, p).dot(sum(ns, type(ns[0])((0.0, 0.0, 0.0)))) < 0:
                p, ns = p[::-1], ns[::-1]
            turned.append(p)
            turned_normals.extend(ns)
        ob = add_mesh_object(name, verts, turned, mat, None)
        me = ob.data
        if len(me.loops) != len(turned_normals):
            raise peer.DaeError(f"mesh {name}: Blender kept {len(me.loops)} of its "
                                f"{len(turned_normals)} corners; its file normals cannot be "
                                "placed")
        me.use_auto_smooth = True
        me.normals_split_custom_set([tuple(n) for n in turned_normals])
        return ob

    peer.add_mesh_object = add_with_file_normals


def no_terminator_offset(info):
    """Shadow rays from the surface itself, as candela traces them: Cycles by default starts
    them from a point lifted off a smooth-shaded triangle (its shadow-terminator geometry
    offset, 0.1), which hides the faceted terminator of a coarse mesh that candela shows."""
    import bpy
    for ob in bpy.data.objects:
        if ob.type == "MESH":
            ob.cycles.shadow_terminator_geometry_offset = 0.0
    info["shadow_terminator_geometry_offset"] = 0.0


# A point light closer to a surface's plane than this fraction of the surface's bounding-box
# diagonal, over the surface, lies in it. Float rounding of file coordinates is ~1e-7 relative.
IN_PLANE_TOLERANCE = 1e-6
# How far the two half-space lamps that stand for such a light sit off the plane, as a fraction
# of the scene's bounding-box diagonal: far beyond rounding (so that a shadow ray to a lamp no
# longer ends on the surface), far below anything a pixel resolves.
IN_PLANE_OFFSET = 1e-5


def point_in_triangle_plane(p, a, b, c, tol):
    """The unit normal of triangle abc when p lies within tol of its plane and over the
    triangle (barycentric coordinates within tol of it), else None."""
    n = (b - a).cross(c - a)
    area2 = n.length
    if area2 == 0.0:
        return None
    n = n / area2
    if abs((p - a).dot(n)) > tol:
        return None
    # Barycentric coordinates of p's projection, each scaled by the triangle's doubled area.
    q = p - n * (p - a).dot(n)
    slack = tol * max((b - a).length, (c - a).length, (c - b).length)
    for u, v in ((a, b), (b, c), (c, a)):
        if (v - u).cross(q - u).dot(n) < -slack:
            return None
    return n


def half_space_emission(ld, axis):
    """Makes point lamp `ld` emit only along directions d with d . axis > 0, at its full
    intensity there: its emission strength times a step of the direction's component along
    `axis`. In a lamp's shader the Geometry node's Incoming vector is the emitted direction (the
    opposite sign lit only the other half-space). A 180-degree spot lamp cannot stand in: one
    lit the wall of the test scene at a quarter of a point lamp's irradiance, as a cosine
    falloff toward the cone's edge would."""
    ld.use_nodes = True
    nt = ld.node_tree
    em = next(n for n in nt.nodes if n.type == "EMISSION")
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    dot = nt.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    nt.links.new(geo.outputs["Incoming"], dot.inputs[0])
    dot.inputs[1].default_value = tuple(axis)
    step = nt.nodes.new("ShaderNodeMath")
    step.operation = "GREATER_THAN"
    nt.links.new(dot.outputs["Value"], step.inputs[0])
    step.inputs[1].default_value = 0.0
    nt.links.new(step.outputs[0], em.inputs["Strength"])


def split_in_plane_point_lights(info):
    """A point light that lies in the plane of a mesh face, over the face, lights both
    half-spaces in full (a shadow ray toward it meets the face only at its own end, which is no
    occlusion), and lights nothing in the plane (cos = 0), as candela renders it. Cycles'
    shadow ray toward such a lamp ends on the face, and rounding decides whether the face
    blocks it: from the far side of a floor the lamp lay in, most of its light was lost. Each
    such lamp becomes two point lamps of the same intensity, one per half-space, each emitting
    only into its own half-space (half_space_emission) and set a hair off the plane on its
    side: neither's shadow rays touch the face any longer, and neither lights the plane or the
    other side (the lamp a hair above a floor would otherwise pour half its power into a spot
    a hair wide under it)."""
    import math
    import bpy
    from mathutils import Matrix, Vector
    meshes = [ob for ob in bpy.data.objects if ob.type == "MESH"]
    lo = Vector((math.inf,) * 3)
    hi = Vector((-math.inf,) * 3)
    boxes = []
    for ob in meshes:
        vs = [ob.matrix_world @ v.co for v in ob.data.vertices]
        if not vs:
            continue
        blo = Vector([min(v[i] for v in vs) for i in range(3)])
        bhi = Vector([max(v[i] for v in vs) for i in range(3)])
        boxes.append((ob, blo, bhi))
        lo = Vector([min(lo[i], blo[i]) for i in range(3)])
        hi = Vector([max(hi[i], bhi[i]) for i in range(3)])
    if not boxes:
        return
    offset = IN_PLANE_OFFSET * (hi - lo).length
    split = []
    for lamp in [ob for ob in bpy.data.objects
                 if ob.type == "LIGHT" and ob.data.type == "POINT"]:
        p = lamp.matrix_world.translation.copy()
        normal = None
        for ob, blo, bhi in boxes:
            tol = IN_PLANE_TOLERANCE * max((bhi - blo).length, 1e-30)
            if any(p[i] < blo[i] - tol or p[i] > bhi[i] + tol for i in range(3)):
                continue
            me = ob.data
            me.calc_loop_triangles()
            for t in me.loop_triangles:
                a, b, c = (ob.matrix_world @ me.vertices[k].co for k in t.vertices)
                normal = point_in_triangle_plane(p, a, b, c, tol)
                if normal is not None:
                    break
            if normal is not None:
                break
        if normal is None:
            continue
        for side in (1.0, -1.0):
            ld = lamp.data.copy()
            ld.name = f"{lamp.data.name}.half{'+' if side > 0 else '-'}"
            half_space_emission(ld, normal * side)
            ob = bpy.data.objects.new(ld.name, ld)
            ob.matrix_world = Matrix.Translation(p + normal * (side * offset))
            bpy.context.scene.collection.objects.link(ob)
        split.append(lamp.name)
        bpy.data.objects.remove(lamp, do_unlink=True)
    info["point_lights_in_a_face_plane"] = split


def emitters_smallest_triangles_first(info):
    """Links the emissive meshes into the scene again in increasing order of their triangles'
    mean area, so that Cycles meets them in that order when it builds its light distribution.

    Cycles 3.4 picks an emissive triangle from a cumulative table of triangle areas that it sums
    in single precision (the running total `totarea` in scene/light.cpp), and weighs the pick
    with the triangle's exact area over the final total. A triangle's slot in the table is the
    rounded difference of two running totals, so where its area is within a few units in the
    last place of the running total its light is sampled too often or too rarely by up to half
    a unit over its area, and the equal triangles of one tessellated sphere all err the same way:
    a sphere of radius 8 mm (20480 triangles) summed after a 0.2 m one was sampled 25 % too
    rarely. Summing the smallest triangles first keeps every running total small beside the
    triangles added to it."""
    import bpy
    emitters = []
    for ob in bpy.data.objects:
        if ob.type != "MESH" or not ob.data.polygons:
            continue
        mats = [m for m in ob.data.materials if m is not None]
        if not any(m.node_tree and any(n.type == "EMISSION" for n in m.node_tree.nodes)
                   for m in mats):
            continue
        me = ob.data
        me.calc_loop_triangles()
        n = len(me.loop_triangles)
        area = sum(t.area for t in me.loop_triangles)
        emitters.append((area / max(n, 1), ob.name, ob))
    emitters.sort(key=lambda e: (e[0], e[1]))
    coll = bpy.context.scene.collection
    for _, _, ob in emitters:
        coll.objects.unlink(ob)
    for _, _, ob in emitters:
        coll.objects.link(ob)
    info["emitters_in_order"] = len(emitters)


def set_world(peer, dae, env_map, info):
    """Replaces the peer script's black world by the ambient lights and the environment map."""
    import bpy
    ambient = [0.0, 0.0, 0.0]
    n_ambient = 0
    for light in dae.lights:
        if light["type"] == "ambient":
            n_ambient += 1
            ambient = [a + c for a, c in zip(ambient, light["spectrum"])]
    # The peer script warned that it ignores ambient lights; this script renders them.
    dae.warnings[:] = [w for w in dae.warnings
                       if not ("<ambient>" in w and "not supported" in w)]
    info["other_lights"] = [l for l in info["other_lights"] if l.get("type") != "ambient"]
    world_info = {"ambient": ambient if n_ambient else None, "env_map": env_map}
    info["world"] = world_info
    if not n_ambient and env_map is None:
        return
    up_index = {"X_UP": 0, "Y_UP": 1, "Z_UP": 2}[dae.up_axis]
    if env_map is not None and dae.up_axis != "Y_UP":
        raise peer.DaeError(f"{dae.path}: an environment map needs a Y_UP file here "
                            f"(this one is {dae.up_axis})")
    world = bpy.context.scene.world
    nt = world.node_tree
    bg = nt.nodes.get("Background")
    bg.inputs["Strength"].default_value = 1.0
    coords = nt.nodes.new("ShaderNodeTexCoord")  # "Generated" is the ray direction here
    xyz = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(coords.outputs["Generated"], xyz.inputs[0])
    terms = []
    if n_ambient:
        # radiance `ambient` where the direction's up component is positive, else 0
        above = nt.nodes.new("ShaderNodeMath")
        above.operation = "GREATER_THAN"
        nt.links.new(xyz.outputs[up_index], above.inputs[0])
        above.inputs[1].default_value = 0.0
        scale = nt.nodes.new("ShaderNodeVectorMath")
        scale.operation = "SCALE"
        scale.inputs[0].default_value = ambient
        nt.links.new(above.outputs[0], scale.inputs["Scale"])
        terms.append(scale.outputs[0])
    if env_map is not None:
        # Spec 2.6: theta = acos(d.y), phi = atan2(-d.z, d.x) + pi, u = phi / 2 pi, row 0 at
        # the zenith. Cycles' equirectangular lookup of a Z-up vector b gives
        # u = (atan2(-b.y, b.x) + pi) / 2 pi and the zenith at the top row, so b = (d.x, d.z, d.y).
        swap = nt.nodes.new("ShaderNodeCombineXYZ")
        nt.links.new(xyz.outputs[0], swap.inputs[0])
        nt.links.new(xyz.outputs[2], swap.inputs[1])
        nt.links.new(xyz.outputs[1], swap.inputs[2])
        tex = nt.nodes.new("ShaderNodeTexEnvironment")
        tex.projection = "EQUIRECTANGULAR"
        tex.interpolation = "Linear"
        tex.image = bpy.data.images.load(env_map, check_existing=False)
        tex.image.colorspace_settings.name = "Linear"
        nt.links.new(swap.outputs[0], tex.inputs["Vector"])
        terms.append(tex.outputs["Color"])
    total = terms[0]
    for t in terms[1:]:
        add = nt.nodes.new("ShaderNodeVectorMath")
        add.operation = "ADD"
        nt.links.new(total, add.inputs[0])
        nt.links.new(t, add.inputs[1])
        total = add.outputs[0]
    nt.links.new(total, bg.inputs["Color"])
    # Importance-sample the world (MIS) from a map of the environment's own resolution: a
    # finer one samples no better, and Cycles builds it by evaluating the world shader at every
    # texel during scene sync, which is part of the time measured (1024 x 512 texels took
    # several seconds). An ambient light alone is constant over each hemisphere.
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = (tex.image.size[0] if env_map is not None
                                          else AMBIENT_MAP_RESOLUTION)
    world_info["sample_map_resolution"] = world.cycles.sample_map_resolution


def main():
    peer_path, env_map, argv = split_args(sys.argv)
    spec = importlib.util.spec_from_file_location("render_cycles", peer_path)
    peer = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(peer)
    pad_short_matrices(peer)
    keep_file_normals(peer)
    build_scene = peer.build_scene

    def build_with_world(dae, args):
        for w in SHORT_MATRICES:
            dae.warn(w)
        info = build_scene(dae, args)
        no_terminator_offset(info)
        split_in_plane_point_lights(info)
        emitters_smallest_triangles_first(info)
        set_world(peer, dae, env_map, info)
        note_ellipsoids(peer, dae)
        return info

    peer.build_scene = build_with_world
    sys.argv = argv
    try:
        peer.main()
    except peer.DaeError as e:
        print(f"[cycles-world] error: {e}", file=sys.stderr)
        sys.exit(2)


main()
