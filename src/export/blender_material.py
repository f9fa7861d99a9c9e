"""A brdf-shop material for Blender (Cycles), written by `brdf-shop export --format blender`.

Run inside Blender (Text editor > Run Script, or `blender --background --python THIS.py`) or by any
Python with the `bpy` module, it creates the node group `brdf-shop NAME` and the material `NAME`
(its lookup images packed into the .blend), ready to assign to an object or to append from a saved
file. Run with flags, it renders brdf-shop's default view instead:

    python3 THIS.py [--env F.exr|F.hdr] [--env-rotation DEG] [--mesh sphere|F.obj|F.ply|F.glb]
                    [--size WxH] [--spp N] [--seed N] [--save M.blend] --out I.exr
    blender --background --python THIS.py -- [the same flags]

the default camera view of brdf-shop (eye (0,0,4), target the origin, up +y, vertical fov 30°, in
brdf-shop's y-up frame; Blender's frame is z-up: brdf-shop (x, y, z) is Blender (x, -z, y)) of the
object under the environment map with direct lighting (Cycles, emitter and BSDF sampling with MIS,
no further bounces), one estimate per sample through each pixel's centre, written as a linear RGBA
OpenEXR (alpha: the object's coverage of the pixel centre), the image `brdf-shop reference`
computes. Without --env the object is lit by a uniform white environment. --env-rotation DEG turns
the map by DEG degrees about brdf-shop's up axis (+y, Blender's +Z), counter-clockwise seen from
above, as `brdf-shop render/reference --env-rotation DEG` do. --save also writes the scene as a
.blend (--out may then be left out).

Run without flags in a file that already holds a material or node group of these names (a cube's
`Material` in Blender's start file, or an earlier run of this script), it takes them over: their
nodes are rebuilt and their users keep them, so the names come out exactly as exported.

Every output (--out, --save) is written one way (class Output): checked before any work (an existing
output must be a regular file; its folder a folder this process can write in), written by Blender
into a private folder that tempfile.mkdtemp creates beside it, then moved onto its name with
os.replace; the private folder is removed on success, refusal or error. An environment map whose
header declares more texels than brdf-shop reads (ENV_MAX_SIDE a side, ENV_MAX_TEXELS in all) is
refused before Blender allocates for it. Every refusal is one line on stderr and exit status 1.

What is exact and what is approximate (docs/exports.md, Blender (Cycles)): the diffuse term is
Cycles' Lambert closure, exactly brdf-shop's. Each facet frame F of a reciprocal lobe (a split lobe
has two, Q and Q^-1, at half weight) is a Beckmann Glossy BSDF whose normal is the facet's mean
normal F z and whose tangent is F (cos phi, sin phi, 0), both taken to world space through
brdf-shop's shading frame (tangent normalize(Z x n) in Blender's frame), with roughness
(alpha_x alpha_y)^(1/4) and Cycles' anisotropy for alpha_x / alpha_y. Cycles' Beckmann closure is
not brdf-shop's facet lobe (its masking term and its 1/cos of the view about the facet normal
differ from brdf-shop's 1/max(cos_i, cos_o) about the surface normal), so a lookup image per facet,
indexed by the view in the facet frame, scales the closure by brdf-shop's directional albedo over
Cycles': the reflected energy matches per view, the shape of each lobe is Cycles'. An
energy-preserving material's compensation terms raise the diffuse closure's colour by their
directional albedo at the view (a lookup image indexed by the view in the local frame): their
energy matches per view, spread over the light as cos θ_i where the terms weight it by
(1 - Ê(ω_i)) cos θ_i.
"""

import math
import os
import shutil
import stat
import struct
import sys
import tempfile

import bpy

# The material, filled in by `brdf-shop export`: the diffuse albedo and, per facet frame, its
# albedo share, rotation (w, x, y, z) in the local shading frame, roughness, tangent angle and
# lookup image (TABLE_SIZE² values, rows from the bottom; texel (u, v) holds the view
# v_f = (x, y, z) in the facet frame with (u, v) = 1/2 + 1/2 (x, y) / (1 + z)); for an
# energy-preserving material COMPENSATION, the lobes' compensation terms' directional albedo
# (r, g, b) per texel of the view in the local frame, laid out the same way (else None); and brdf-shop's
# limits on environment maps (ENV_MAX_SIDE texels a side, ENV_MAX_TEXELS in all, ENV_MAX_BYTES of
# file), the ones its own loader applies.


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
# "inverse-frame" puts Q^-1 in place of each facet frame Q, "env-rotation-negated" turns the
# environment by -DEG for --env-rotation DEG, "no-compensation" leaves the compensation terms out.
# Unset in normal use.
FAULT = os.environ.get("BRDF_SHOP_BLENDER_FAULT", "")


class UserError(Exception):
    pass


def show(path):
    """A path for a message: its first 200 characters, control characters and undecodable bytes
    escaped, so that a message stays one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(path)[:200])


def reason(e):
    """The one-line reason of an OSError (its strerror) or of Blender's RuntimeError (its last line,
    without Blender's `Error: ` prefix)."""
    if isinstance(e, OSError) and e.strerror:
        return e.strerror
    lines = [l.strip() for l in str(e).splitlines() if l.strip()]
    text = lines[-1] if lines else type(e).__name__
    return (text[len("Error: ") :] if text.startswith("Error: ") else text)[:200]


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


def own_datablock(collection, name):
    """The datablock of the open file (not linked from a library) named exactly `name`, or None."""
    return next((d for d in collection if d.name == name and d.library is None), None)


def lookup_image(name, table):
    """A TABLE_SIZE² float image of `table` (rows from the bottom): one value a texel (grey), or an
    (r, g, b) tuple."""
    size = TABLE_SIZE
    old = own_datablock(bpy.data.images, name)
    if old is not None:  # a lookup image of an earlier run: its node group is rebuilt
        bpy.data.images.remove(old)
    img = bpy.data.images.new(name, size, size, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    pixels = [1.0] * (4 * size * size)
    for k, v in enumerate(table):
        pixels[4 * k : 4 * k + 3] = v if isinstance(v, tuple) else (v, v, v)
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
    group_name = "brdf-shop " + name
    tree = own_datablock(bpy.data.node_groups, group_name)
    if tree is not None and tree.bl_idname == "ShaderNodeTree":
        tree.nodes.clear()
        tree.interface.clear()
    else:
        tree = bpy.data.node_groups.new(group_name, "ShaderNodeTree")
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

    def lookup(image, v, column):
        """The colour of `image` at the view v = (x, y, z), at (u, v) = 1/2 + 1/2 (x, y) / (1 + z)."""
        vx, vy, vz = v
        s = g.math("DIVIDE", 0.5, g.math("ADD", vz, 1.0, column), column)
        uv = g.node("ShaderNodeCombineXYZ", column + 1)
        g.link(g.math("MULTIPLY_ADD", vx, s, column + 1, 0.5), uv.inputs[0])
        g.link(g.math("MULTIPLY_ADD", vy, s, column + 1, 0.5), uv.inputs[1])
        tex = g.node("ShaderNodeTexImage", column + 2, interpolation="Linear", extension="EXTEND")
        tex.image = image
        g.link(uv.outputs[0], tex.inputs["Vector"])
        return tex.outputs["Color"]

    shaders = []
    if any(d > 0.0 for d in DIFFUSE) or COMPENSATION is not None:
        d = g.node("ShaderNodeBsdfDiffuse", 6)
        d.inputs["Color"].default_value = (DIFFUSE[0], DIFFUSE[1], DIFFUSE[2], 1.0)
        d.inputs["Roughness"].default_value = 0.0
        if COMPENSATION is not None and FAULT != "no-compensation":
            # The lobes' compensation terms: their directional albedo at the view in the local frame
            # raises the diffuse colour (docs/exports.md, Blender (Cycles), Energy-preserving
            # materials).
            split = g.node("ShaderNodeSeparateXYZ", 2)
            g.link(local, split.inputs[0])
            image = lookup_image("brdf-shop %s compensation" % name, COMPENSATION)
            terms = lookup(image, tuple(split.outputs), 3)
            g.link(g.vmath("ADD", terms, tuple(DIFFUSE), 5), d.inputs["Color"])
        shaders.append(d.outputs[0])
    for k, f in enumerate(FACETS):
        q = conj(f.rotation) if FAULT == "inverse-frame" else f.rotation
        phi = f.tangent_angle + (0.5 * math.pi if FAULT == "tangent-90" else 0.0)
        normal = world(rotate(q, (0.0, 0.0, 1.0)))
        tangent = world(rotate(q, (math.cos(phi), math.sin(phi), 0.0)))
        # The view in the facet frame and its lookup coordinates.
        v = tuple(g.vmath("DOT_PRODUCT", local, rotate(q, axis), 3) for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
        ratio = lookup(lookup_image("brdf-shop %s facet %d" % (name, k), f.table), v, 3)
        colour = g.vmath("MULTIPLY", ratio, tuple(f.colour), 5)
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
    """The material NAME: the node group into the Material Output. A material and node group of
    these names already in the open file are taken over (their nodes rebuilt, their users kept), so
    that the names are exactly NAME and `brdf-shop NAME`, not NAME.001."""
    tree = build_group(NAME)
    mat = own_datablock(bpy.data.materials, NAME) or bpy.data.materials.new(NAME)
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
        raise UserError("%s: no such file" % show(path))
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
        raise UserError("%s: %s" % (show(path), str(e).strip().splitlines()[-1][:200] if str(e).strip() else "not read"))
    objs = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if not objs:
        raise UserError("%s: no mesh in the file" % show(path))
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
        raise UserError("%s: the mesh has no vertices" % show(path))
    lo = [min(v.co[i] for v in mesh.vertices) for i in range(3)]
    hi = [max(v.co[i] for v in mesh.vertices) for i in range(3)]
    centre = [(a + b) * 0.5 for a, b in zip(lo, hi)]
    radius = 0.5 * math.sqrt(sum((b - a) ** 2 for a, b in zip(lo, hi)))
    if not radius > 0.0:
        raise UserError("%s: the mesh has no extent" % show(path))
    for v in mesh.vertices:
        v.co = [(v.co[i] - centre[i]) / radius for i in range(3)]
    if not mesh.has_custom_normals:
        mesh.shade_smooth()
    return obj


def read_exact(f, n):
    data = f.read(n)
    if len(data) != n:
        raise ValueError("the header is cut short")
    return data


def read_name(f):
    """A NUL-terminated attribute name or type of an OpenEXR header (at most 255 bytes)."""
    out = bytearray()
    while True:
        c = read_exact(f, 1)
        if c == b"\0":
            return bytes(out)
        out += c
        if len(out) > 255:
            raise ValueError("an attribute name longer than 255 bytes")


def exr_sizes(f):
    """The data window size (width, height) of each part of an OpenEXR file, from its headers (the
    size Blender allocates for)."""
    if read_exact(f, 4) != b"\x76\x2f\x31\x01":
        raise ValueError("not an OpenEXR file")
    multipart = bool(struct.unpack("<I", read_exact(f, 4))[0] & 0x1000)
    sizes = []
    while len(sizes) < 1024:
        window, attributes = None, 0
        while True:
            name = read_name(f)
            if not name:
                break
            attributes += 1
            if attributes > 4096:
                raise ValueError("more than 4096 header attributes")
            read_name(f)
            n = struct.unpack("<i", read_exact(f, 4))[0]
            if n < 0:
                raise ValueError("an attribute of negative size")
            if name == b"dataWindow" and n == 16:
                x0, y0, x1, y1 = struct.unpack("<4i", read_exact(f, 16))
                window = (x1 - x0 + 1, y1 - y0 + 1)
            else:
                f.seek(n, 1)
        if multipart and attributes == 0 and sizes:
            return sizes  # the empty header that ends a multi-part file's headers
        if window is None:
            raise ValueError("a header without a dataWindow")
        sizes.append(window)
        if not multipart:
            return sizes
    raise ValueError("more than 1024 parts")


def hdr_sizes(f):
    """The size (width, height) a Radiance .hdr file's resolution line declares."""
    head = f.read(65536)
    if not head.startswith(b"#?"):
        raise ValueError("not a Radiance HDR file")
    end = head.find(b"\n\n")
    line = head[end + 2 :].split(b"\n", 1)
    if end < 0 or len(line) < 2:
        raise ValueError("no resolution line in its first 65536 bytes")
    t = line[0].split()
    axes = [a[1:2] for a in t[0::2]]
    signs_ok = all(a[:1] in (b"-", b"+") for a in t[0::2])
    if len(t) != 4 or sorted(axes) != [b"X", b"Y"] or not signs_ok:
        raise ValueError("not a resolution line: %r" % line[0][:40].decode("latin-1"))
    try:
        a, b = int(t[1]), int(t[3])
    except ValueError:
        raise ValueError("not a resolution line: %r" % line[0][:40].decode("latin-1"))
    return [(b, a) if axes[0] == b"Y" else (a, b)]


def check_env(path):
    """Refuses, before Blender reads it, an environment map that is not a regular file, is larger
    than ENV_MAX_BYTES, or whose header declares more texels than brdf-shop reads: ENV_MAX_SIDE a
    side, ENV_MAX_TEXELS in all (`brdf-shop export` fills them in from src/scene/env.rs). Blender
    allocates a declared size in full before it reads a pixel."""
    shown = show(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".exr", ".hdr"):
        raise UserError("--env: %r is not an .exr or .hdr file" % shown)
    try:
        # Non-blocking, so that a FIFO is refused instead of waited on.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        raise UserError("%s: no such file" % shown)
    except OSError as e:
        raise UserError("--env: %s: %s" % (shown, reason(e)))
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise UserError("--env: %s: not a regular file" % shown)
        if st.st_size > ENV_MAX_BYTES:
            raise UserError("--env: %s: %d bytes, more than the limit of %d" % (shown, st.st_size, ENV_MAX_BYTES))
        try:
            sizes = exr_sizes(f) if ext == ".exr" else hdr_sizes(f)
        except (ValueError, struct.error) as e:
            kind = "OpenEXR" if ext == ".exr" else "Radiance HDR"
            raise UserError("--env: %s: not a readable %s file: %s" % (shown, kind, e))
        except OSError as e:
            raise UserError("--env: %s: %s" % (shown, reason(e)))
    for w, h in sizes:
        declares = "--env: %s: the header declares %dx%d" % (shown, w, h)
        if w < 1 or h < 1:
            raise UserError("%s, an empty image" % declares)
        if w > ENV_MAX_SIDE or h > ENV_MAX_SIDE:
            raise UserError("%s, longer than the limit of %d texels a side" % (declares, ENV_MAX_SIDE))
        if w * h > ENV_MAX_TEXELS:
            raise UserError("%s, more than the limit of %d texels" % (declares, ENV_MAX_TEXELS))


def load_env(path):
    try:
        img = bpy.data.images.load(os.path.abspath(path), check_existing=False)
        img.colorspace_settings.name = "Linear Rec.709"
        if img.size[0] == 0 or img.size[1] == 0:
            raise RuntimeError("no pixels")
    except RuntimeError as e:
        raise UserError("%s: not a readable image (%s)" % (show(path), str(e).strip()[:120]))
    return img


def world(env, rotation=0.0):
    """The environment: brdf-shop looks a direction d up at u = fract(atan2(d.x, -d.z) / 2pi),
    v = acos(d.y) / pi; Blender's equirectangular lookup of the same direction (x, -z, y) is that
    turned by -90° about Z, so the direction is turned by +90° about Z first.

    `rotation` (degrees) turns the map as brdf-shop's `--env-rotation` does (src/scene/env.rs,
    `Environment::rotated`): what lay in direction d lies in R_y(rotation) d, so the radiance from d
    is the map's at R_y(-rotation) d. The change of frame is a rotation taking brdf-shop's +y to
    Blender's +Z, so R_y(a) is R_Z(a) in Blender's frame, and the Mapping node (type Vector: its
    output is its Euler rotation applied to its input) looks D up at R_Z(90°) R_Z(-rotation) D: a Z
    rotation of 90° - rotation (tests/export_blender.rs renders both signs against `brdf-shop
    reference --env-rotation`). The turn is taken as brdf-shop takes it, (rotation / 360) mod 1 of a
    full turn, which also keeps the node's single-precision angle within [-270°, 90°]."""
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
        turn = ((-rotation if FAULT == "env-rotation-negated" else rotation) / 360.0) % 1.0
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.5 * math.pi - 2.0 * math.pi * turn)
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


def build_scene(env, rotation, mesh, width, height, spp, seed):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mat = build_material()
    obj = sphere_object() if mesh in (None, "sphere") else mesh_object(mesh)
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    scene.camera = camera(width, height)
    scene.world = world(env, rotation)
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


class Output:
    """An output file (--out, --save), written one way: `open` checks it before any work (an existing
    output must be a regular file, as brdf-shop's own outputs) and creates a private folder beside it
    with tempfile.mkdtemp (a fresh name of a few bytes, mode 0700: nothing can be planted in it, a
    folder this process cannot write in fails here, and an output name of 255 bytes still fits);
    `write` has Blender write the file there under a short fixed name (with any file Blender writes
    beside it, a .blend1 backup included) and moves it onto the output's name with os.replace, with
    the permission bits of the file it replaces; `close` removes the private folder."""

    def __init__(self, flag, path, ext):
        self.flag, self.shown, self.ext = flag, path, ext
        self.path = os.path.abspath(path)
        self.folder = None

    def fail(self, why):
        return UserError("%s: %s: %s" % (self.flag, show(self.shown), why))

    def check_existing(self):
        """Refuses an existing output that is a folder or not a regular file (a device, FIFO or
        socket, through symlinks too); checked at `open` and again just before the rename."""
        try:
            mode = os.stat(self.path).st_mode
        except FileNotFoundError:
            return None
        except OSError as e:
            raise self.fail(reason(e))
        if stat.S_ISDIR(mode):
            raise self.fail("is a folder, not a file")
        if not stat.S_ISREG(mode):
            raise self.fail("is not a regular file (a device, FIFO or socket); outputs replace regular files only")
        return stat.S_IMODE(mode)

    def open(self):
        if not self.path.lower().endswith(self.ext):
            raise self.fail("only %s is written" % self.ext)
        parent = os.path.dirname(self.path)
        if not os.path.isdir(parent):
            there = "is not a folder" if os.path.lexists(parent) else "does not exist"
            raise self.fail("the folder %s %s" % (show(parent), there))
        self.check_existing()
        try:
            self.folder = tempfile.mkdtemp(prefix=".brdf-shop-", dir=parent)
        except OSError as e:
            raise self.fail("cannot write in %s: %s" % (show(parent), reason(e)))
        return self

    def write(self, produce):
        """`produce(tmp)` writes the whole file at `tmp` (in the private folder); then it replaces
        the output."""
        tmp = os.path.join(self.folder, "o" + self.ext)
        try:
            produce(tmp)
            if not stat.S_ISREG(os.lstat(tmp).st_mode):
                raise self.fail("Blender wrote no file")
            mode = self.check_existing()
            if mode is not None:
                os.chmod(tmp, mode)
            os.replace(tmp, self.path)
        except (OSError, RuntimeError) as e:  # bpy.ops raise RuntimeError with Blender's report
            raise self.fail(reason(e))

    def close(self):
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)
            self.folder = None


def render(scene, path, width, height):
    """Renders the image into `path`'s folder (the output's private folder), sets alpha to the
    coverage and writes it at `path`."""
    import numpy as np

    raw = os.path.join(os.path.dirname(path), "r.exr")
    scene.render.filepath = raw
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(raw, check_existing=False)
    try:
        img.colorspace_settings.name = "Linear Rec.709"
        px = np.empty(width * height * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        px[3::4] = coverage(scene, width, height)
        img.pixels.foreach_set(px)
        img.filepath_raw = path
        img.file_format = "OPEN_EXR"
        img.use_half_precision = False
        img.save()
    finally:
        bpy.data.images.remove(img)


def parse_size(text):
    try:
        w, h = text.lower().split("x")
        w, h = int(w), int(h)
    except ValueError:
        raise UserError("--size: %r is not WxH" % text[:80])
    if not (1 <= w <= 8192 and 1 <= h <= 8192):
        raise UserError("--size: %dx%d is outside 1..8192 per side" % (w, h))
    return w, h


def parse_rotation(text):
    """--env-rotation: any finite number of degrees, as brdf-shop takes it."""
    try:
        deg = float(text)
    except ValueError:
        raise UserError("--env-rotation: %r is not a number of degrees" % text[:80])
    if not math.isfinite(deg):
        raise UserError("--env-rotation: %r is not a finite number of degrees" % text[:80])
    return deg


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

    FLAGS = ("--env", "--env-rotation", "--mesh", "--size", "--spp", "--seed", "--save", "--out")

    @staticmethod
    def parse(args):
        got = {}
        i = 0
        while i < len(args):
            a = args[i]
            if a in ("-h", "--help"):
                raise UserError("usage: [--env F.exr|F.hdr] [--env-rotation DEG] [--mesh sphere|F.obj|F.ply|F.glb] [--size WxH] [--spp N] [--seed N] [--save M.blend] --out I.exr")
            if a not in Parser.FLAGS:
                raise UserError("%r: unknown argument (known: %s)" % (a[:80], ", ".join(Parser.FLAGS)))
            if i + 1 >= len(args):
                raise UserError("%s: needs a value" % a)
            got[a[2:]] = args[i + 1]
            i += 2
        return got


def main(argv=None):
    args = script_args(argv)
    outputs = []
    script = os.path.basename(__file__) if "__file__" in globals() else "brdf-shop"
    try:
        if not args:
            mat = build_material()
            group = next(n.node_tree for n in mat.node_tree.nodes if n.type == "GROUP")
            print("brdf-shop: created material %r (node group %r)" % (mat.name, group.name))
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
        rotation = parse_rotation(a.get("env-rotation", "0"))
        out, save = a.get("out"), a.get("save")
        if out is None and save is None:
            raise UserError("--out: missing (or give --save M.blend)")
        both = out is not None and save is not None and os.path.exists(out) and os.path.exists(save)
        if both and os.path.samefile(out, save):
            raise UserError("--save: %s: names the same file as --out" % show(save))
        env = a.get("env")
        if env is not None:
            check_env(env)
        for flag, path, ext in (("--save", save, ".blend"), ("--out", out, ".exr")):
            if path is not None:
                outputs.append(Output(flag, path, ext).open())
        scene = build_scene(env, rotation, a.get("mesh", "sphere"), width, height, spp, seed)
        for o in outputs:
            if o.flag == "--save":
                # A copy, so the open file keeps no name of the private folder; paths kept as they
                # are (the environment map's absolute), not made relative to the private folder.
                o.write(
                    lambda tmp: bpy.ops.wm.save_as_mainfile(
                        filepath=tmp, check_existing=False, copy=True, relative_remap=False
                    )
                )
            else:
                o.write(lambda tmp: render(scene, tmp, width, height))
    except UserError as e:
        print("%s: %s" % (script, e), file=sys.stderr)
        return 1
    except OSError as e:
        print("%s: %s: %s" % (script, show(e.filename) if e.filename else "error", reason(e)), file=sys.stderr)
        return 1
    except MemoryError:
        print("%s: out of memory" % script, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("%s: interrupted" % script, file=sys.stderr)
        return 130
    finally:
        for o in outputs:
            o.close()
    return 0


if __name__ == "__main__":
    code = main()
    if code:
        sys.exit(code)
