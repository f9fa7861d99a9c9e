"""Test harness for the exported Mitsuba plug-in (tests/export_mitsuba.rs): loads the plug-in file
given as argv[1] (which registers `brdfshop`), reads direction pairs `wix wiy wiz wox woy woz`
(the local frame of docs/model.md, Frames and conventions, f32 values) from argv[2] and prints, per
pair, through Mitsuba's BSDF interface with a shading frame equal to the local frame:

    eval: f·cos θ_i (3 numbers) and pdf
    sample: for the view ω_o of the pair and two random numbers: the sampled ω_i (3), the returned
            weight (3), its pdf, and eval(ω_i)/pdf computed separately (3)

as `E r g b pdf` and `S x y z wr wg wb pdf er eg eb` lines.
"""

import importlib.util
import sys

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
spec = importlib.util.spec_from_file_location("brdfshop_plugin", sys.argv[1])
plugin = importlib.util.module_from_spec(spec)
spec.loader.exec_module(plugin)

rows = [[float(v) for v in line.split()] for line in open(sys.argv[2]) if line.strip()]
n = len(rows)
col = lambda k: mi.Float([r[k] for r in rows])
wi = mi.Vector3f(col(0), col(1), col(2))
wo = mi.Vector3f(col(3), col(4), col(5))

bsdf = mi.load_dict({"type": "brdfshop"})
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.n = mi.Normal3f(0.0, 0.0, 1.0)
si.sh_frame = mi.Frame3f(mi.Vector3f(1.0, 0.0, 0.0), mi.Vector3f(0.0, 1.0, 0.0), mi.Vector3f(0.0, 0.0, 1.0))
si.wi = wo  # Mitsuba's si.wi points to the viewer: brdf-shop's ω_o
ctx = mi.BSDFContext()

value = bsdf.eval(ctx, si, wi)
pdf = bsdf.pdf(ctx, si, wi)

sampler = mi.load_dict({"type": "independent"})
sampler.seed(7, n)
bs, weight = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d())
value_s = bsdf.eval(ctx, si, bs.wo)
pdf_s = bsdf.pdf(ctx, si, bs.wo)
ratio = dr.select(pdf_s > 0, value_s / dr.select(pdf_s > 0, pdf_s, 1.0), 0.0)

def arr(x):
    return [float(v) for v in x]

cols = [arr(value.x), arr(value.y), arr(value.z), arr(pdf)]
scols = [arr(bs.wo.x), arr(bs.wo.y), arr(bs.wo.z), arr(weight.x), arr(weight.y), arr(weight.z), arr(bs.pdf),
         arr(ratio.x), arr(ratio.y), arr(ratio.z)]
out = []
for i in range(n):
    out.append("E " + " ".join(repr(c[i]) for c in cols))
    out.append("S " + " ".join(repr(c[i]) for c in scols))
sys.stdout.write("\n".join(out) + "\n")
