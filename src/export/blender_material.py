"""A brdf-shop material for Blender (Cycles), written by `brdf-shop export --format blender`.

Run inside Blender (Text editor > Run Script, or `blender --background --python THIS.py`) or by any
Python with the `bpy` module, it creates the node group `brdf-shop NAME` and the material `NAME`
(its lookup images packed into the .blend), ready to assign to an object or to append from a saved
file. Run with flags, it renders brdf-shop's default view instead:

    python3 THIS.py [--env F.exr|F.hdr] [--mesh sphere|F.obj|F.ply|F.glb] [--size WxH] [--spp N]
                    [--seed N] [--save M.blend] --out I.exr
    blender --background --python THIS.py -- [the same flags]

the default camera view of brdf-shop (eye (0,0,4), target the origin, up +y, vertical fov 30°, in
brdf-shop's y-up frame; Blender's frame is z-up: brdf-shop (x, y, z) is Blender (x, -z, y)) of the
object under the environment map with direct lighting (Cycles, emitter and BSDF sampling with MIS,
no further bounces), one estimate per sample through each pixel's centre, written as a linear RGBA
OpenEXR (alpha: the object's coverage of the pixel centre), the image `brdf-shop reference`
computes. Without --env the object is lit by a uniform white environment. --save also writes the
scene as a .blend (--out may then be left out).

What is exact and what is approximate (docs/exports.md, Blender (Cycles)): the diffuse term is
Cycles' Lambert closure, exactly brdf-shop's. Each facet frame F of a reciprocal lobe (a split lobe
has two, Q and Q^-1, at half weight) is a Beckmann Glossy BSDF whose normal is the facet's mean
normal F z and whose tangent is F (cos phi, sin phi, 0), both taken to world space through
brdf-shop's shading frame (tangent normalize(Z x n) in Blender's frame), with roughness
(alpha_x alpha_y)^(1/4) and Cycles' anisotropy for alpha_x / alpha_y. Cycles' Beckmann closure is
not brdf-shop's facet lobe (its masking term and its 1/cos of the view about the facet normal
differ from brdf-shop's 1/max(cos_i, cos_o) about the surface normal), so a lookup image per facet,
indexed by the view in the facet frame, scales the closure by brdf-shop's directional albedo over
Cycles': the reflected energy matches per view, the shape of each lobe is Cycles'.
"""

import math
import os
import sys

import bpy

# The material, filled in by `brdf-shop export`: the diffuse albedo and, per facet frame, its
# albedo share, rotation (w, x, y, z) in the local shading frame, roughness, tangent angle and
# lookup image (TABLE_SIZE² values, rows from the bottom; texel (u, v) holds the view
# v_f = (x, y, z) in the facet frame with (u, v) = 1/2 + 1/2 (x, y) / (1 + z)).


class Facet:
    def __init__(self, colour, rotation, alpha_x, alpha_y, tangent_angle, table):
        self.colour = colour
        self.rotation = rotation
        self.alpha_x = alpha_x
        self.alpha_y = alpha_y
        self.tangent_angle = tangent_angle
        self.table = table


# @MATERIAL_DATA@

# Test hook (tests/export_blender.rs, negative checks): "tangent-90" turns every tangent by 90°,
# "inverse-frame" puts Q^-1 in place of each facet frame Q. Unset in normal use.
FAULT = os.environ.get("BRDF_SHOP_BLENDER_FAULT", "")


class UserError(Exception):
    pass


# ---- Vectors and quaternions (w, x, y, z), brdf-shop's local shading frame. ----


def rotate(q, v):
    """v + w t + u x t with t = 2 u x v (the formula of glam and the shaders)."""
    w, u = q[0], (q[1], q[2], q[3])

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    t = tuple(2.0 * c for c in cross(u, v))
    c = cross(u, t)
    return tuple(v[i] + w * t[i] + c[i] for i in range(3))


def conj(q):
    return (q[0], -q[1], -q[2], -q[3])


def cycles_roughness(alpha_x, alpha_y):
    """Roughness and anisotropy of Cycles' Glossy BSDF for (alpha_x along the tangent, alpha_y):
    Cycles takes alpha = roughness², then alpha_x = alpha (1 - A), alpha_y = alpha / (1 - A) for
    A >= 0 and alpha_x = alpha / (1 + A), alpha_y = alpha (1 + A) for A < 0, A clamped to ±0.99
    (intern/cycles/kernel/svm/closure.h)."""
    roughness = (alpha_x * alpha_y) ** 0.25
    ratio = math.sqrt(alpha_x / alpha_y)
    anisotropy = 1.0 - ratio if ratio <= 1.0 else 1.0 / ratio - 1.0
    return min(roughness, 1.0), max(-0.99, min(0.99, anisotropy))


# ---- The node group and the material. ----


class Graph:
    """Adds nodes to a node tree, laid out in columns."""

    def __init__(self, tree):
        self.tree = tree
        self.row = 0

    def node(self, kind, column, **props):
        n = self.tree.nodes.new(kind)
        n.location = (column * 220.0, -self.row * 40.0)
        self.row += 1
        for k, v in props.items():
            setattr(n, k, v)
        return n

    def link(self, out, inp):
        self.tree.links.new(out, inp)

    def vmath(self, op, a, b=None, column=1):
        n = self.node("ShaderNodeVectorMath", column, operation=op)
        for sock, val in ((n.inputs[0], a), (n.inputs[1], b)):
            if val is None:
                continue
            if isinstance(val, tuple):
                sock.default_value = val
            else:
                self.link(val, sock)
        return n.outputs["Value" if op == "DOT_PRODUCT" else "Vector"]

    def math(self, op, a, b, column=1, c=None):
        n = self.node("ShaderNodeMath", column, operation=op)
        for sock, val in ((n.inputs[0], a), (n.inputs[1], b), (n.inputs[2], c)):
            if val is None:
                continue
            if isinstance(val, float):
                sock.default_value = val
            else:
                self.link(val, sock)
        return n.outputs[0]


def lookup_image(name, table):
    size = TABLE_SIZE
    img = bpy.data.images.new(name, size, size, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    pixels = [1.0] * (4 * size * size)
    for k, v in enumerate(table):
        pixels[4 * k : 4 * k + 3] = (v, v, v)
    img.pixels.foreach_set(pixels)
    # Packed as 32-bit OpenEXR, so a saved and reopened .blend renders the same image.
    img.file_format = "OPEN_EXR"
    img.use_half_precision = False
    img.pack()
    return img


def build_group(name):
    """The node group `brdf-shop NAME`: brdf-shop's shading frame from the shading normal N and the
    view I (Geometry node), a Diffuse BSDF, and per facet a Glossy BSDF whose colour is its albedo
    share times its lookup image at the view in the facet frame, all added."""
    tree = bpy.data.node_groups.new("brdf-shop " + name, "ShaderNodeTree")
    tree.interface.new_socket("BSDF", in_out="OUTPUT", socket_type="NodeSocketShader")
    g = Graph(tree)
    out = g.node("NodeGroupOutput", 8)
    geo = g.node("ShaderNodeNewGeometry", 0)
    n, view = geo.outputs["Normal"], geo.outputs["Incoming"]
    # brdf-shop's tangent normalize(Y x n) in its y-up frame is normalize(Z x n) in Blender's z-up
    # one (the change of frame is a rotation); b = n x t.
    t = g.vmath("NORMALIZE", g.vmath("CROSS_PRODUCT", (0.0, 0.0, 1.0), n))
    b = g.vmath("CROSS_PRODUCT", n, t)

    def world(c, column=2):
        """The local-frame vector c in world space: c_x t + c_y b + c_z n."""
        terms = [g.vmath("SCALE", axis, None, column) for axis in (t, b, n)]
        for s, comp in zip(terms, c):
            s.node.inputs["Scale"].default_value = comp
        return g.vmath("ADD", g.vmath("ADD", terms[0], terms[1], column), terms[2], column)

    # The view in the local frame, (I.t, I.b, I.n).
    local = g.node("ShaderNodeCombineXYZ", 2)
    for i, axis in enumerate((t, b, n)):
        g.link(g.vmath("DOT_PRODUCT", view, axis), local.inputs[i])
    local = local.outputs[0]

    shaders = []
    if any(d > 0.0 for d in DIFFUSE):
        d = g.node("ShaderNodeBsdfDiffuse", 6)
        d.inputs["Color"].default_value = (DIFFUSE[0], DIFFUSE[1], DIFFUSE[2], 1.0)
        d.inputs["Roughness"].default_value = 0.0
        shaders.append(d.outputs[0])
    for k, f in enumerate(FACETS):
        q = conj(f.rotation) if FAULT == "inverse-frame" else f.rotation
        phi = f.tangent_angle + (0.5 * math.pi if FAULT == "tangent-90" else 0.0)
        normal = world(rotate(q, (0.0, 0.0, 1.0)))
        tangent = world(rotate(q, (math.cos(phi), math.sin(phi), 0.0)))
        # The view in the facet frame and its lookup coordinates.
        vx, vy, vz = (g.vmath("DOT_PRODUCT", local, rotate(q, axis), 3) for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
        s = g.math("DIVIDE", 0.5, g.math("ADD", vz, 1.0, 3), 3)
        uv = g.node("ShaderNodeCombineXYZ", 4)
        g.link(g.math("MULTIPLY_ADD", vx, s, 4, 0.5), uv.inputs[0])
        g.link(g.math("MULTIPLY_ADD", vy, s, 4, 0.5), uv.inputs[1])
        tex = g.node("ShaderNodeTexImage", 5, interpolation="Linear", extension="EXTEND")
        tex.image = lookup_image("brdf-shop %s facet %d" % (name, k), f.table)
        g.link(uv.outputs[0], tex.inputs["Vector"])
        colour = g.vmath("MULTIPLY", tex.outputs["Color"], tuple(f.colour), 5)
        roughness, anisotropy = cycles_roughness(f.alpha_x, f.alpha_y)
        gl = g.node("ShaderNodeBsdfGlossy", 6, distribution="BECKMANN")
        g.link(colour, gl.inputs["Color"])
        gl.inputs["Roughness"].default_value = roughness
        gl.inputs["Anisotropy"].default_value = anisotropy
        gl.inputs["Rotation"].default_value = 0.0
        g.link(normal, gl.inputs["Normal"])
        g.link(tangent, gl.inputs["Tangent"])
        shaders.append(gl.outputs[0])
    if not shaders:
        black = g.node("ShaderNodeBsdfDiffuse", 6)
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        shaders.append(black.outputs[0])
    # A balanced tree of Add Shader nodes.
    while len(shaders) > 1:
        nxt = []
        for i in range(0, len(shaders) - 1, 2):
            add = g.node("ShaderNodeAddShader", 7)
            g.link(shaders[i], add.inputs[0])
            g.link(shaders[i + 1], add.inputs[1])
            nxt.append(add.outputs[0])
        if len(shaders) % 2:
            nxt.append(shaders[-1])
        shaders = nxt
    g.link(shaders[0], out.inputs[0])
    return tree


def build_material():
    """The material NAME: the node group into the Material Output."""
    tree = build_group(NAME)
    mat = bpy.data.materials.new(NAME)
    if mat.node_tree is None:  # Blender before 5.0 makes the node tree on request
        mat.use_nodes = True
    mat.node_tree.nodes.clear()
    group = mat.node_tree.nodes.new("ShaderNodeGroup")
    group.node_tree = tree
    output = mat.node_tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (300.0, 0.0)
    mat.node_tree.links.new(group.outputs[0], output.inputs["Surface"])
    # The correction bends the closures' normals toward the geometric one: the facet normals are
    # meant as given.
    mat.cycles.use_bump_map_correction = False
    return mat


# ---- The ready scene. ----


def sphere_object(segments=256, rings=128):
    """A unit UV sphere about Z (brdf-shop's y axis), smooth-shaded: its interpolated vertex normals
    stand for the sphere's own normals. (bmesh's sphere operator takes seconds at this size.)"""
    verts = [(0.0, 0.0, 1.0)]
    for j in range(1, rings):
        theta = math.pi * j / rings
        z, r = math.cos(theta), math.sin(theta)
        for i in range(segments):
            phi = 2.0 * math.pi * i / segments
            verts.append((r * math.cos(phi), r * math.sin(phi), z))
    verts.append((0.0, 0.0, -1.0))
    south = len(verts) - 1

    def ring(j, i):
        return 1 + (j - 1) * segments + i % segments

    faces = [(0, ring(1, i), ring(1, i + 1)) for i in range(segments)]
    for j in range(1, rings - 1):
        faces += [(ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)) for i in range(segments)]
    faces += [(ring(rings - 1, i + 1), ring(rings - 1, i), south) for i in range(segments)]
    mesh = bpy.data.meshes.new("sphere")
    mesh.from_pydata(verts, [], faces)
    mesh.validate()
    mesh.shade_smooth()
    obj = bpy.data.objects.new("sphere", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def mesh_object(path):
    """The mesh file's objects joined into one, centred on its bounding-box centre and scaled to a
    bounding sphere of radius 1, as brdf-shop places meshes. The importers turn y-up files into
    Blender's z-up frame, (x, y, z) -> (x, -z, y), as brdf-shop's frame maps to Blender's."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".obj", ".ply", ".glb"):
        raise UserError("--mesh: %r is not sphere, an .obj, .ply or .glb file" % path[:80])
    if not os.path.isfile(path):
        raise UserError("%s: no such file" % path[:200])
    before = set(bpy.data.objects)
    try:
        if ext == ".obj":
            bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
        elif ext == ".ply":
            bpy.ops.wm.ply_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
        else:
            import addon_utils

            addon_utils.enable("io_scene_gltf2", default_set=True)
            bpy.ops.import_scene.gltf(filepath=path)
    except Exception as e:  # the importers raise RuntimeError with Blender's report
        raise UserError("%s: %s" % (path[:200], str(e).strip().splitlines()[-1][:200] if str(e).strip() else "not read"))
    objs = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if not objs:
        raise UserError("%s: no mesh in the file" % path[:200])
    for o in bpy.data.objects:
        o.select_set(o in objs)
    bpy.context.view_layer.objects.active = objs[0]
    if len(objs) > 1:
        bpy.ops.object.join()
    obj = bpy.context.view_layer.objects.active
    for o in [o for o in bpy.data.objects if o not in before and o != obj]:
        bpy.data.objects.remove(o)
    bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
    mesh = obj.data
    if len(mesh.vertices) == 0:
        raise UserError("%s: the mesh has no vertices" % path[:200])
    lo = [min(v.co[i] for v in mesh.vertices) for i in range(3)]
    hi = [max(v.co[i] for v in mesh.vertices) for i in range(3)]
    centre = [(a + b) * 0.5 for a, b in zip(lo, hi)]
    radius = 0.5 * math.sqrt(sum((b - a) ** 2 for a, b in zip(lo, hi)))
    if not radius > 0.0:
        raise UserError("%s: the mesh has no extent" % path[:200])
    for v in mesh.vertices:
        v.co = [(v.co[i] - centre[i]) / radius for i in range(3)]
    if not mesh.has_custom_normals:
        mesh.shade_smooth()
    return obj


def load_env(path):
    try:
        img = bpy.data.images.load(os.path.abspath(path), check_existing=False)
        img.colorspace_settings.name = "Linear Rec.709"
        if img.size[0] == 0 or img.size[1] == 0:
            raise RuntimeError("no pixels")
    except RuntimeError as e:
        raise UserError("%s: not a readable image (%s)" % (path[:200], str(e).strip()[:120]))
    return img


def world(env):
    """The environment: brdf-shop looks a direction d up at u = fract(atan2(d.x, -d.z) / 2pi),
    v = acos(d.y) / pi; Blender's equirectangular lookup of the same direction (x, -z, y) is that
    turned by -90° about Z, so the direction is turned by +90° about Z first."""
    w = bpy.data.worlds.new("brdf-shop environment")
    if w.node_tree is None:
        w.use_nodes = True
    nodes, links = w.node_tree.nodes, w.node_tree.links
    nodes.clear()
    bg = nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = 1.0
    out = nodes.new("ShaderNodeOutputWorld")
    links.new(bg.outputs[0], out.inputs["Surface"])
    if env is None:
        bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    else:
        coords = nodes.new("ShaderNodeTexCoord")
        mapping = nodes.new("ShaderNodeMapping")
        mapping.vector_type = "VECTOR"
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.5 * math.pi)
        tex = nodes.new("ShaderNodeTexEnvironment")
        tex.image = load_env(env)
        tex.interpolation = "Linear"
        links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
        links.new(tex.outputs["Color"], bg.inputs["Color"])
    return w


def camera(width, height):
    cam = bpy.data.cameras.new("brdf-shop camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(30.0)
    cam.clip_start, cam.clip_end = 0.01, 100.0
    obj = bpy.data.objects.new("brdf-shop camera", cam)
    # brdf-shop's eye (0, 0, 4) looking at the origin, up +y: Blender's (0, -4, 0) looking along +Y,
    # up +Z (the camera looks down its -Z and is turned 90° about X).
    obj.location = (0.0, -4.0, 0.0)
    obj.rotation_euler = (0.5 * math.pi, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def build_scene(env, mesh, width, height, spp, seed):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mat = build_material()
    obj = sphere_object() if mesh in (None, "sphere") else mesh_object(mesh)
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    scene.camera = camera(width, height)
    scene.world = world(env)
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.film_transparent = False
    r.dither_intensity = 0.0
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_mode = "RGBA"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.seed = seed
    c.use_adaptive_sampling = False
    c.use_denoising = False
    # Direct lighting only, like brdf-shop's reference: no bounce after the first hit.
    c.max_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.light_sampling_threshold = 0.0
    # A pixel-centre estimate: Cycles' box filter ignores its width, a Gaussian of width 0.01
    # samples the centre.
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    return scene


def coverage(scene, width, height):
    """1 where the ray through the pixel centre hits the object, rows from the bottom."""
    from mathutils import Vector

    depsgraph = bpy.context.evaluated_depsgraph_get()
    origin = Vector((0.0, -4.0, 0.0))
    tan = math.tan(math.radians(15.0))
    out = []
    for j in range(height):
        y = (2.0 * (j + 0.5) / height - 1.0) * tan
        for i in range(width):
            x = (2.0 * (i + 0.5) / width - 1.0) * tan * width / height
            hit = scene.ray_cast(depsgraph, origin, Vector((x, 1.0, y)).normalized())[0]
            out.append(1.0 if hit else 0.0)
    return out


def render(scene, out, width, height):
    """Renders to a temp file beside `out`, sets alpha to the coverage, then renames it: an existing
    output is replaced only by a complete image."""
    folder = os.path.dirname(os.path.abspath(out))
    base = os.path.join(folder, ".%s.%d" % (os.path.basename(out), os.getpid()))
    raw, tmp = base + ".render.exr", base + ".tmp.exr"
    try:
        scene.render.filepath = raw
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)
        import numpy as np

        img = bpy.data.images.load(raw, check_existing=False)
        img.colorspace_settings.name = "Linear Rec.709"
        px = np.empty(width * height * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        px[3::4] = coverage(scene, width, height)
        img.pixels.foreach_set(px)
        img.filepath_raw = tmp
        img.file_format = "OPEN_EXR"
        img.use_half_precision = False
        img.save()
        os.replace(tmp, out)
    finally:
        for p in (raw, tmp):
            if os.path.exists(p):
                os.remove(p)


def parse_size(text):
    try:
        w, h = text.lower().split("x")
        w, h = int(w), int(h)
    except ValueError:
        raise UserError("--size: %r is not WxH" % text[:80])
    if not (1 <= w <= 8192 and 1 <= h <= 8192):
        raise UserError("--size: %dx%d is outside 1..8192 per side" % (w, h))
    return w, h


def script_args(argv):
    """The script's own flags: after `--` inside Blender; all arguments under plain Python."""
    if argv is not None:
        return list(argv)
    if "--" in sys.argv:
        return sys.argv[sys.argv.index("--") + 1 :]
    if bpy.app.binary_path and os.path.basename(sys.argv[0] if sys.argv else "").lower().startswith("blender"):
        return []
    return sys.argv[1:]


class Parser:
    """argparse without its usage text and exit: one line per error."""

    FLAGS = ("--env", "--mesh", "--size", "--spp", "--seed", "--save", "--out")

    @staticmethod
    def parse(args):
        got = {}
        i = 0
        while i < len(args):
            a = args[i]
            if a in ("-h", "--help"):
                raise UserError("usage: [--env F.exr|F.hdr] [--mesh sphere|F.obj|F.ply|F.glb] [--size WxH] [--spp N] [--seed N] [--save M.blend] --out I.exr")
            if a not in Parser.FLAGS:
                raise UserError("%r: unknown argument (known: %s)" % (a[:80], ", ".join(Parser.FLAGS)))
            if i + 1 >= len(args):
                raise UserError("%s: needs a value" % a)
            got[a[2:]] = args[i + 1]
            i += 2
        return got


def main(argv=None):
    args = script_args(argv)
    try:
        if not args:
            mat = build_material()
            print("brdf-shop: created material %r (node group %r)" % (mat.name, "brdf-shop " + NAME))
            if PAPER_NOTE:
                print("brdf-shop: note: %s" % PAPER_NOTE)
            return 0
        a = Parser.parse(args)
        width, height = parse_size(a.get("size", "512x512"))
        try:
            spp, seed = int(a.get("spp", "256")), int(a.get("seed", "0"))
        except ValueError:
            raise UserError("--spp/--seed: not a whole number")
        if not 1 <= spp <= 1 << 24:
            raise UserError("--spp: %d is outside 1..16777216" % spp)
        if not 0 <= seed < 1 << 31:
            raise UserError("--seed: %d is outside 0..2147483647" % seed)
        out, save = a.get("out"), a.get("save")
        if out is None and save is None:
            raise UserError("--out: missing (or give --save M.blend)")
        for flag, path, ext in (("--out", out, ".exr"), ("--save", save, ".blend")):
            if path is None:
                continue
            if not path.lower().endswith(ext):
                raise UserError("%s: %r: only %s is written" % (flag, path[:80], ext))
            folder = os.path.dirname(os.path.abspath(path))
            if not os.path.isdir(folder) or os.path.isdir(path):
                raise UserError("%s: %r: its folder does not exist or it is a folder" % (flag, path[:200]))
        env = a.get("env")
        if env is not None:
            if os.path.splitext(env)[1].lower() not in (".exr", ".hdr"):
                raise UserError("--env: %r is not an .exr or .hdr file" % env[:200])
            if not os.path.isfile(env):
                raise UserError("%s: no such file" % env[:200])
        scene = build_scene(env, a.get("mesh", "sphere"), width, height, spp, seed)
        if save is not None:
            bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(save), check_existing=False)
        if out is not None:
            render(scene, out, width, height)
    except UserError as e:
        print("%s: %s" % (os.path.basename(__file__) if "__file__" in globals() else "brdf-shop", e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    code = main()
    if code:
        sys.exit(code)
