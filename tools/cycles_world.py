"""Runs the Cycles peer script (render_cycles.py) with the scene's infinite lights as Cycles'
world, which the peer script leaves black: every <ambient> light of the scene (uniform
radiance over the hemisphere around the file's up axis, as candela reads it) and, with
--env-map, a lat-long environment map in candela's (the scene-format spec's) orientation.

It also warns (in the JSON line's warnings) about CGL spheres under a transform that is not a
similarity: candela renders the ellipsoid, the peer script a sphere.

Run inside Blender, like the peer script, with two options of its own among the peer script's:

    blender -b --factory-startup --python-exit-code 1 -P tools/cycles_world.py -- \
        --peer-script PATH/render_cycles.py [--env-map sky.exr] --scene ... (peer options)

The peer script's JSON line gains "world": what the world holds. Without ambient lights and
--env-map it changes nothing. Only Y_UP files take an environment map here: for other up axes
the mapping of the map onto directions would need candela's rotation of the file, so the script
stops with an error rather than render a wrongly oriented sky.
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
    build_scene = peer.build_scene

    def build_with_world(dae, args):
        info = build_scene(dae, args)
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
