"""What the Blender export's Diffuse closure costs against an energy-preserving material's
compensation terms under a map (docs/exports.md, Blender (Cycles), Energy-preserving materials).

The Blender material reflects each lobe's term `rho (1 - E(wi)) (1 - E(wo)) c` as a Diffuse closure
of colour `rho (1 - E(wo)) c pi deficit` (`deficit` the cosine-weighted mean of `1 - E`): the same
albedo at every view, with the light weighted by `cos` instead of `(1 - E(wi)) cos`. This renders
the exported Mitsuba plug-in of the material (exact) three ways with the same samples: as it is,
with each term replaced by the closure's, and without the terms; it prints the relative L1 over the
object of the closure's image against the exact one, the terms' share of the exact image, and the
closure's error relative to the terms alone. Cycles is not involved: what it measures is the
closure's substitution alone.

    brdf-shop export --material M.brdf.json --format mitsuba --out M.py
    target/mitsuba-venv/bin/python3 docs/perf/models/blender-compensation-as-diffuse.py M.py MAP.exr [SIZE] [SPP]
"""

import importlib.util
import math
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")


def main():
    plugin, env = sys.argv[1], sys.argv[2]
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 32
    spp = int(sys.argv[4]) if len(sys.argv) > 4 else 4096
    spec = importlib.util.spec_from_file_location("plugin", plugin)
    p = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(p)
    if p.TABLES is None:
        sys.exit("%s: not an energy-preserving material" % plugin)
    # deficit_k by a 512² midpoint rule over the cosine-weighted hemisphere.
    n = 512
    i = dr.arange(mi.UInt32, n * n)
    u1, u2 = (mi.Float64(i // n) + 0.5) / n, (mi.Float64(i % n) + 0.5) / n
    r, a = dr.sqrt(u1), 2.0 * math.pi * u2
    w = (r * dr.cos(a), r * dr.sin(a), dr.sqrt(1.0 - u1))
    for t in p.TABLES:
        t.deficit = dr.mean(1.0 - mi.Float64(t.albedo(w)))[0]
    exact_term = p.Table.term

    def closure_term(self, wi, wo):
        return p.F64((p.f32(1.0) - self.albedo(wo)) * p.f32(self.scale)) * self.deficit

    images = {}
    for name, term in (("exact", exact_term), ("closure", closure_term), ("none", lambda s, wi, wo: p.F64(0.0))):
        p.Table.term = term
        images[name] = p.render(env, None, size, size, spp, 0, 0.0)
    covered = images["exact"][..., 3] >= 0.5
    exact, closure, none = (images[k][covered][:, :3].astype(np.float64) for k in ("exact", "closure", "none"))
    diff = np.abs(closure - exact).sum()
    print(
        "%s: closure against exact %.2f %% (relative L1 over the object), terms' share %.1f %%, closure's error "
        "relative to the terms %.1f %%" % (env, 100.0 * diff / exact.sum(), 100.0 * np.abs(exact - none).sum() / exact.sum(), 100.0 * diff / np.abs(exact - none).sum())
    )


if __name__ == "__main__":
    main()
