#version 460
// The editor's window: the mesh view and the canvas placed side by side, each scaled by its exposure
// and encoded as sRGB (the same curve as `imageio::srgb8`), the snap marker on the canvas, and the
// window's grey everywhere else. The tool panel and the BRDF graph are drawn over it by egui.
// A view rendered smaller than its place (the editor's preview frames) is magnified bilinearly.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) writeonly uniform image2D window;
layout(set = 0, binding = 1, rgba32f) readonly uniform image2D mesh;
layout(set = 0, binding = 2, rgba32f) readonly uniform image2D canvas;
layout(push_constant) uniform Push {
    uvec4 window_size;  // W, H, mesh view height, 1 to draw the marker
    uvec4 views;        // mesh view x, width; canvas x, side
    vec4 scale;         // mesh view scale (exposure / summed samples), canvas exposure, marker x, y (pixels)
    vec4 background;    // window grey, 0..1 per channel; the backdrop's scale (brightness / summed samples)
    uvec4 region;       // the rectangle this dispatch writes: x, y, width, height
    uvec4 sources;      // the mesh view's image width, height; the canvas image's side; the samples it sums
} pc;

// What this pipeline writes (the others' pixels are left as they are; an `if` runs both sides on
// llvmpipe, so each part is a pipeline of its own): 1 the mesh view, 2 the canvas, 4 the grey.
layout(constant_id = 0) const uint PARTS = 7u;
const bool MESH = (PARTS & 1u) != 0u;
const bool CANVAS = (PARTS & 2u) != 0u;
const bool GREY = (PARTS & 4u) != 0u;

vec3 srgb(vec3 v) {
    vec3 x = clamp(v, 0.0, 1.0);
    x = mix(x, vec3(0.0), isnan(x));
    return mix(1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, 12.92 * x, lessThanEqual(x, vec3(0.0031308)));
}

// Where pixel q of a place of `place` pixels falls in an image of `source` pixels, for bilinear
// filtering: the four texels' corner (clamped with the other three inside) and the weights.
void magnify(ivec2 q, ivec2 place, ivec2 source, out ivec2 a, out ivec2 b, out vec2 t) {
    vec2 s = (vec2(q) + 0.5) * vec2(source) / vec2(place) - 0.5;
    vec2 f = floor(s);
    t = s - f;
    a = clamp(ivec2(f), ivec2(0), source - 1);
    b = clamp(ivec2(f) + 1, ivec2(0), source - 1);
}

// The mesh view's radiance and coverage at pixel q of its place (`place` pixels).
vec4 mesh_at(ivec2 q, ivec2 place) {
    ivec2 source = ivec2(pc.sources.xy);
    if (source == place) return imageLoad(mesh, q);
    ivec2 a, b;
    vec2 t;
    magnify(q, place, source, a, b, t);
    vec4 top = mix(imageLoad(mesh, a), imageLoad(mesh, ivec2(b.x, a.y)), t.x);
    vec4 bottom = mix(imageLoad(mesh, ivec2(a.x, b.y)), imageLoad(mesh, b), t.x);
    return mix(top, bottom, t.y);
}

// The same for the canvas.
vec3 canvas_at(ivec2 q, ivec2 place) {
    ivec2 source = ivec2(pc.sources.zz);
    if (source == place) return imageLoad(canvas, q).rgb;
    ivec2 a, b;
    vec2 t;
    magnify(q, place, source, a, b, t);
    vec3 top = mix(imageLoad(canvas, a).rgb, imageLoad(canvas, ivec2(b.x, a.y)).rgb, t.x);
    vec3 bottom = mix(imageLoad(canvas, ivec2(a.x, b.y)).rgb, imageLoad(canvas, b).rgb, t.x);
    return mix(top, bottom, t.y);
}

void main() {
    ivec2 p = ivec2(pc.region.xy + gl_GlobalInvocationID.xy);
    if (gl_GlobalInvocationID.x >= pc.region.z || gl_GlobalInvocationID.y >= pc.region.w) return;
    if (p.x >= int(pc.window_size.x) || p.y >= int(pc.window_size.y)) return;
    vec3 c = pc.background.rgb;
    int mx = int(pc.views.x), mw = int(pc.views.y), cx = int(pc.views.z), cs = int(pc.views.w);
    bool in_mesh = p.x >= mx && p.x < mx + mw && p.y < int(pc.window_size.z);
    bool in_canvas = !in_mesh && p.x >= cx && p.x < cx + cs && p.y < cs;
    if (MESH && in_mesh) {
        // The object at the exposure, the backdrop (alpha 0) at its own brightness. The image is a
        // sum over `sources.w` samples, alpha (the coverage) summed with them: the pixel's coverage
        // is alpha over that count, and weighs the two scales (a magnified silhouette blends them).
        vec4 m = mesh_at(ivec2(p.x - mx, p.y), ivec2(mw, pc.window_size.z));
        float cover = clamp(m.a / float(max(pc.sources.w, 1u)), 0.0, 1.0);
        c = srgb(m.rgb * mix(pc.background.w, pc.scale.x, cover));
    } else if (CANVAS && in_canvas) {
        c = srgb(canvas_at(ivec2(p.x - cx, p.y), ivec2(cs)) * pc.scale.y);
        ivec2 m = ivec2(pc.scale.zw);
        ivec2 d = abs(p - m);
        if (pc.window_size.w == 1u && ((d.y == 0 && d.x <= 6) || (d.x == 0 && d.y <= 6))) {
            c = vec3(255.0, 210.0, 60.0) / 255.0;
        }
    } else if (!GREY || in_mesh || in_canvas) {
        return;
    }
    imageStore(window, p, vec4(c, 1.0));
}
