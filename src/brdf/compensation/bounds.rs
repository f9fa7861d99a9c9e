//! Certified bounds of one box of facet slopes at a table cell's corner views (docs/model.md,
//! Energy preservation, The certificate).
//!
//! The facets of one frame are `w = M (X, Y, 1)` for standard normal `X, Y`, with `M = R A`, `R` a
//! rotation (the facet frame, then the table's frame about the normal) and `A` the slope scales
//! `s_x, s_y` about the tangent angle, so that `D = |w|² = 1 + s_x² X² + s_y² Y²`. At view slope
//! `V` (`Ṽ = (V_x, V_y, 1)`), `F = f + 1 = 2 N / D` with `N = w_z (w·Ṽ)`, a product of two affine
//! functions of `(X, Y)`. Over a box `b` this gives
//! - first-order bounds `S ≥ f ≥ I` from the box's image in world slopes (a convex quadrilateral),
//! - second-order bounds `U2 ≥ ∫_b f dP ≥ L2` from the Taylor model of `F` about the box's centre:
//!   value and gradient at the centre, the Hessian bounded over the box by interval arithmetic,
//!   against bounds of the Gaussian's box moments that involve no cancellation,
//!
//! and from them the box's weight at each corner view (one of three convex majorants of
//! `∫_b clamp(f, 0, 1) dP`, the same at every corner) and its certified gap.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use glam::{DMat3, DVec3};

/// Relative margin of the first-order bounds and of the box's `D` range (a few dozen operations).
const REL: f64 = 1.0e-12;
/// Relative margin of the second-order bounds, on the magnitudes of their terms.
const REL2: f64 = 1.0e-11;

/// `Φ(b) − Φ(a)` for `a ≤ b`, from the upper tail where `a > 0` (no cancellation), within about
/// `10⁻¹⁶` absolute (`libm::erfc` is within an ulp or two).
pub fn mass(a: f64, b: f64) -> f64 {
    let tail = |x: f64| 0.5 * libm::erfc(x * FRAC_1_SQRT_2);
    if a > 0.0 {
        tail(a) - tail(b)
    } else if b < 0.0 {
        tail(-b) - tail(-a)
    } else {
        1.0 - tail(-a) - tail(b)
    }
}

fn phi(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * PI).sqrt()
}

/// One frame's facets in the table's frame: `M` and the slope scales (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct Facets {
    pub m: DMat3,
    pub sx: f64,
    pub sy: f64,
}

/// A box of standard slopes `[x0, x1] × [y0, y1]` (dyadic pieces of the first boxes: its centre
/// and widths are exact).
#[derive(Clone, Copy, Debug)]
pub struct Box2 {
    pub x0: f64,
    pub x1: f64,
    pub y0: f64,
    pub y1: f64,
}

impl Box2 {
    pub fn split(&self) -> [Box2; 4] {
        let (xm, ym) = (0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1));
        [
            Box2 { x0: self.x0, x1: xm, y0: self.y0, y1: ym },
            Box2 { x0: xm, x1: self.x1, y0: self.y0, y1: ym },
            Box2 { x0: self.x0, x1: xm, y0: ym, y1: self.y1 },
            Box2 { x0: xm, x1: self.x1, y0: ym, y1: self.y1 },
        ]
    }
}

/// Bounds of the Gaussian's moments over one side `[x0, x1]` about its centre `c` (width `d`):
/// `p = Φ(x1) − Φ(x0)`; `φ_min d³/12 ≤ ∫ (x − c)² φ ≤ φ_max d³/12`; `|∫ (x − c) φ| ≤ sup|φ'| d³/12`
/// (`∫ (x − c) (φ(x) − φ(c))`); `∫ |x − c| φ ≤ φ_max d²/4`.
#[derive(Clone, Copy)]
struct Side {
    p: f64,
    m2_lo: f64,
    m2_hi: f64,
    m1: f64,
    mabs: f64,
}

fn side(x0: f64, x1: f64) -> Side {
    let d = x1 - x0;
    let near = 0.0f64.clamp(x0, x1);
    let pmax = phi(near) * (1.0 + REL);
    let pmin = phi(x0).min(phi(x1)) * (1.0 - REL);
    let one_in = (x0 <= 1.0 && x1 >= 1.0) || (x0 <= -1.0 && x1 >= -1.0);
    let dphi = if one_in { phi(1.0) } else { (x0.abs() * phi(x0)).max(x1.abs() * phi(x1)) } * (1.0 + REL);
    let k = d * d * d / 12.0;
    Side { p: mass(x0, x1), m2_lo: pmin * k, m2_hi: pmax * k, m1: dphi * k, mabs: pmax * d * d / 4.0 }
}

/// A closed interval, with the magnitude of what it was computed from (its rounding is relative
/// to that, not to its ends).
#[derive(Clone, Copy)]
struct Iv {
    lo: f64,
    hi: f64,
    mag: f64,
}

impl Iv {
    fn of(lo: f64, hi: f64) -> Iv {
        Iv { lo, hi, mag: lo.abs().max(hi.abs()) }
    }
    fn c(v: f64) -> Iv {
        Iv::of(v, v)
    }
    fn mul(self, o: Iv) -> Iv {
        let p = [self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi];
        let lo = p.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let hi = p.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        Iv { lo, hi, mag: self.mag * o.mag }
    }
    fn add(self, o: Iv) -> Iv {
        Iv { lo: self.lo + o.lo, hi: self.hi + o.hi, mag: self.mag + o.mag }
    }
    fn neg(self) -> Iv {
        Iv { lo: -self.hi, hi: -self.lo, mag: self.mag }
    }
    fn scale(self, k: f64) -> Iv {
        self.mul(Iv::c(k))
    }
    /// Widened by `rel` times its magnitude: a rigorous enclosure of the exact interval.
    fn widen(self, rel: f64) -> Iv {
        Iv { lo: self.lo - rel * self.mag, hi: self.hi + rel * self.mag, mag: self.mag }
    }
}

/// The least and largest of `x²` over `[x0, x1]`.
fn sq_range(x0: f64, x1: f64) -> (f64, f64) {
    let hi = (x0 * x0).max(x1 * x1);
    let lo = if x0 <= 0.0 && x1 >= 0.0 { 0.0 } else { (x0 * x0).min(x1 * x1) };
    (lo, hi)
}

/// What one box gives at each corner view of a cell: the weights (the same majorant at every
/// corner), the certified gap (weight minus a certified lower bound of `∫_b clamp(f, 0, 1) dP`, at
/// the worst corner), and the part of it that the best majorant per corner alone would leave
/// (`split_gap`: what splitting the box can shrink; the rest is the facets whose `f` crosses 1 or
/// 0 within the cell's views).
#[derive(Clone, Copy, Debug)]
pub struct Weights {
    pub w: [f64; 4],
    pub gap: f64,
    pub split_gap: f64,
}

/// The data of one box that does not depend on the view.
struct BoxData {
    p: f64,
    /// The corners' half vectors.
    ws: [DVec3; 4],
    d_min: f64,
    d_max: f64,
    wz_max: f64,
    /// World slopes of the corners and the range of their squared length (regular boxes).
    pq: [[f64; 2]; 4],
    r_min2: f64,
    r_max2: f64,
}

/// The box's weights at the corner views `corners[..n]` (`n` 2 or 4).
pub fn weights(f: &Facets, b: &Box2, corners: &[[f64; 2]; 4], n: usize) -> Weights {
    let m = &f.m;
    let cx = [b.x0, b.x1, b.x1, b.x0];
    let cy = [b.y0, b.y0, b.y1, b.y1];
    let ws: [DVec3; 4] = std::array::from_fn(|k| m.x_axis * cx[k] + m.y_axis * cy[k] + m.z_axis);
    let tol = 1e-12 * ws.iter().map(|w| w.abs().element_sum()).fold(0.0, f64::max);
    if ws.iter().all(|w| w.z < -tol) {
        // Every half vector under the horizon: g = 0.
        return Weights { w: [0.0; 4], gap: 0.0, split_gap: 0.0 };
    }
    let regular = ws.iter().all(|w| w.z > tol);
    let (x2, y2) = (sq_range(b.x0, b.x1), sq_range(b.y0, b.y1));
    let (s2x, s2y) = (f.sx * f.sx, f.sy * f.sy);
    let d_min = (1.0 + s2x * x2.0 + s2y * y2.0) * (1.0 - REL);
    let d_max = (1.0 + s2x * x2.1 + s2y * y2.1) * (1.0 + REL);
    let wz_max = ws.iter().map(|w| w.z).fold(f64::NEG_INFINITY, f64::max);
    let mut bd = BoxData { p: 0.0, ws, d_min, d_max, wz_max, pq: [[0.0; 2]; 4], r_min2: 0.0, r_max2: 0.0 };
    if regular {
        let pq = ws.map(|w| [w.x / w.z, w.y / w.z]);
        let r2 = pq.map(|[p, q]| p * p + q * q);
        let rmax2 = r2.iter().fold(0.0f64, |a, &r| a.max(r)) * (1.0 + 1e-10) + 1e-12;
        bd.r_min2 = (min_distance2(&pq) * (1.0 - 1e-10) - 1e-12 * (1.0 + rmax2)).max(0.0);
        bd.r_max2 = rmax2;
        bd.pq = pq;
    }
    // First-order bounds at every corner; saturated boxes need nothing more.
    let mut s = [0.0; 4];
    let mut i = [f64::NEG_INFINITY; 4];
    for k in 0..n {
        let v = corners[k];
        // f ≤ 2 h_z |Ṽ| − 1 (near the horizon, where the world slopes blow up).
        let sp = 2.0 * bd.wz_max.max(0.0) / bd.d_min.sqrt() * (1.0 + v[0] * v[0] + v[1] * v[1]).sqrt() - 1.0;
        s[k] = sp * (1.0 + REL) + REL;
        if regular {
            let (sf, i1) = first_order(&bd, v);
            s[k] = s[k].min(sf);
            i[k] = i1;
        }
    }
    if s[..n].iter().all(|&v| v <= 0.0) {
        return Weights { w: [0.0; 4], gap: 0.0, split_gap: 0.0 };
    }
    let (sxs, sys) = (mass(b.x0, b.x1), mass(b.y0, b.y1));
    bd.p = sxs * sys;
    if regular && i[..n].iter().all(|&v| v >= 1.0) {
        return Weights { w: [bd.p; 4], gap: 0.0, split_gap: 0.0 };
    }
    let mut u2 = [f64::INFINITY; 4];
    let mut l2 = [f64::NEG_INFINITY; 4];
    if regular {
        let so = SecondBox::new(f, b, &bd);
        for k in 0..n {
            let r = so.at(corners[k]);
            s[k] = s[k].min(r.f_hi - 1.0);
            i[k] = i[k].max(r.f_lo - 1.0);
            u2[k] = r.u - bd.p;
            l2[k] = r.l - bd.p;
        }
    }
    combine(bd.p, regular, &s, &i, &u2, &l2, n)
}

/// The box's weights from its bounds at each corner: `S ≥ f ≥ I` pointwise, `U2 ≥ ∫ f dP ≥ L2`.
fn combine(p: f64, regular: bool, s: &[f64; 4], i: &[f64; 4], u2: &[f64; 4], l2: &[f64; 4], n: usize) -> Weights {
    let sat0 = s[..n].iter().all(|&v| v <= 0.0);
    let sat1 = regular && i[..n].iter().all(|&v| v >= 1.0);
    if sat0 {
        return Weights { w: [0.0; 4], gap: 0.0, split_gap: 0.0 };
    }
    if sat1 {
        return Weights { w: [p; 4], gap: 0.0, split_gap: 0.0 };
    }
    // Majorants of ∫ max(0, f) (u0) and minorants of ∫ (f − 1) (l1) at each corner.
    let mut u0 = [0.0; 4];
    let mut l1 = [0.0; 4];
    let mut lb = [0.0; 4];
    for k in 0..n {
        let (sk, ik) = (s[k], i[k]);
        let mut u = p * sk.max(0.0);
        if ik >= 0.0 {
            u = u.min(u2[k]);
        } else if sk > 0.0 && u2[k].is_finite() {
            // The chord of max(0, ·) over [I, S].
            u = u.min(sk / (sk - ik) * (u2[k] - ik * p) * (1.0 + REL));
        }
        u0[k] = u;
        l1[k] = (p * (ik - 1.0)).max(l2[k] - p);
        // A certified lower bound of ∫ clamp(f, 0, 1) dP (for the splitting only).
        let mut lo = p * ik.clamp(0.0, 1.0);
        if l2[k].is_finite() {
            if sk <= 1.0 && (ik >= 0.0 || sk > 0.0) {
                lo = lo.max(l2[k]);
            } else if (0.0..1.0).contains(&ik) && sk > 1.0 {
                // The chord of min(1, ·) over [I, S].
                lo = lo.max(ik * p + (1.0 - ik) / (sk - ik) * (l2[k] - ik * p));
            }
        }
        lb[k] = lo;
    }
    let opt_b = u0;
    let opt_c: [f64; 4] = std::array::from_fn(|k| u0[k] - l1[k]);
    let sum = |w: &[f64; 4]| w[..n].iter().sum::<f64>();
    let (sa, sb, sc) = (p * n as f64, sum(&opt_b), sum(&opt_c));
    let w = if sb <= sa && sb <= sc {
        opt_b
    } else if sc <= sa {
        opt_c
    } else {
        [p; 4]
    };
    let mut gap = 0.0f64;
    let mut split_gap = 0.0f64;
    for k in 0..n {
        gap = gap.max(w[k] - lb[k]);
        let best = p.min(u0[k]).min(opt_c[k]);
        split_gap = split_gap.max(best - lb[k]);
    }
    Weights { w, gap, split_gap }
}

/// `S ≥ f ≥ I` over a regular box at view `v`: the numerator `1 + p V_x + q V_y` is affine in the
/// world slopes (extremes at the quadrilateral's corners), the denominator `1 + p² + q²` between
/// the squared distances of its nearest and farthest points.
fn first_order(bd: &BoxData, v: [f64; 2]) -> (f64, f64) {
    let num = bd.pq.map(|[p, q]| 1.0 + p * v[0] + q * v[1]);
    let nmax = num.iter().fold(f64::NEG_INFINITY, |a, &n| a.max(n));
    let nmin = num.iter().fold(f64::INFINITY, |a, &n| a.min(n));
    let (dmin, dmax) = (1.0 + bd.r_min2, 1.0 + bd.r_max2);
    let mag = 1.0 + bd.pq.iter().map(|[p, q]| p.abs() + q.abs()).fold(0.0, f64::max) * (1.0 + v[0].abs() + v[1].abs());
    let margin = 8.0 * REL * mag;
    let s = 2.0 * if nmax >= 0.0 { nmax / dmin } else { nmax / dmax } - 1.0 + margin;
    let i = 2.0 * if nmin >= 0.0 { nmin / dmax } else { nmin / dmin } - 1.0 - margin;
    (s, i)
}

/// The second-order bounds of one regular box at one view: `u ≥ ∫_b F dP ≥ l` and `f_hi ≥ F ≥ f_lo`
/// pointwise on the box.
struct Second {
    u: f64,
    l: f64,
    f_hi: f64,
    f_lo: f64,
}

/// The view-independent parts of the Taylor model of `F = 2 N / D` over one regular box.
struct SecondBox {
    a: DVec3,
    b: DVec3,
    /// The corners' half vectors, and the magnitudes of their terms.
    ws: [DVec3; 4],
    wms: [DVec3; 4],
    wz: Iv,
    /// `D_X`, `D_Y` over the box, `1/D`, `1/D²`, `1/D³`.
    dx: Iv,
    dy: Iv,
    id: Iv,
    id2: Iv,
    id3: Iv,
    dxx: f64,
    dyy: f64,
    /// The centre's half vector, its magnitudes, `D` and its gradient there.
    wc: DVec3,
    wcm: DVec3,
    xc: f64,
    yc: f64,
    dc: f64,
    dxc: f64,
    dyc: f64,
    /// Half widths.
    hx: f64,
    hy: f64,
    p: f64,
    mx: Side,
    my: Side,
}

impl SecondBox {
    fn new(f: &Facets, b: &Box2, bd: &BoxData) -> SecondBox {
        let (a, bb, w0) = (f.m.x_axis, f.m.y_axis, f.m.z_axis);
        let cx = [b.x0, b.x1, b.x1, b.x0];
        let cy = [b.y0, b.y0, b.y1, b.y1];
        let wms: [DVec3; 4] = std::array::from_fn(|k| w0.abs() + a.abs() * cx[k].abs() + bb.abs() * cy[k].abs());
        let lo = bd.ws.iter().map(|w| w.z).fold(f64::INFINITY, f64::min);
        let hi = bd.ws.iter().map(|w| w.z).fold(f64::NEG_INFINITY, f64::max);
        let mag = wms.iter().map(|w| w.z).fold(0.0, f64::max);
        let wz = Iv { lo, hi, mag }.widen(1e-14);
        let (s2x, s2y) = (f.sx * f.sx, f.sy * f.sy);
        let id = Iv::of(1.0 / bd.d_max, 1.0 / bd.d_min).widen(1e-15);
        let id2 = id.mul(id);
        let id3 = id2.mul(id);
        let (xc, yc) = (0.5 * (b.x0 + b.x1), 0.5 * (b.y0 + b.y1));
        SecondBox {
            a,
            b: bb,
            ws: bd.ws,
            wms,
            wz,
            dx: Iv::of(2.0 * s2x * b.x0, 2.0 * s2x * b.x1),
            dy: Iv::of(2.0 * s2y * b.y0, 2.0 * s2y * b.y1),
            id,
            id2,
            id3,
            dxx: 2.0 * s2x,
            dyy: 2.0 * s2y,
            wc: w0 + a * xc + bb * yc,
            wcm: w0.abs() + a.abs() * xc.abs() + bb.abs() * yc.abs(),
            xc,
            yc,
            dc: 1.0 + s2x * xc * xc + s2y * yc * yc,
            dxc: 2.0 * s2x * xc,
            dyc: 2.0 * s2y * yc,
            hx: 0.5 * (b.x1 - b.x0),
            hy: 0.5 * (b.y1 - b.y0),
            p: bd.p,
            mx: side(b.x0, b.x1),
            my: side(b.y0, b.y1),
        }
    }

    fn at(&self, v: [f64; 2]) -> Second {
        let (a, bb) = (self.a, self.b);
        let vt = DVec3::new(v[0], v[1], 1.0);
        let vabs = vt.abs();
        let (av, bv) = (a.dot(vt), bb.dot(vt));
        // s = w·Ṽ, affine over the box: extremes at its corners.
        let sv = {
            let vals = self.ws.map(|w| w.dot(vt));
            let lo = vals.iter().fold(f64::INFINITY, |x, &y| x.min(y));
            let hi = vals.iter().fold(f64::NEG_INFINITY, |x, &y| x.max(y));
            let mag = self.wms.iter().map(|w| w.dot(vabs)).fold(0.0, f64::max);
            Iv { lo, hi, mag }.widen(1e-14)
        };
        let wz = self.wz;
        let n = wz.mul(sv);
        let nx = sv.scale(a.z).add(wz.scale(av));
        let ny = sv.scale(bb.z).add(wz.scale(bv));
        let nxx = 2.0 * a.z * av;
        let nyy = 2.0 * bb.z * bv;
        let nxy = a.z * bv + bb.z * av;
        let (dx, dy, id, id2, id3) = (self.dx, self.dy, self.id, self.id2, self.id3);
        // ∂²(2N/D) = 2 (N_ij/D − (N_i D_j + N_j D_i)/D² − N D_ij/D² + 2 N D_i D_j/D³).
        let hess = |nij: f64, ni: Iv, nj: Iv, di: Iv, dj: Iv, dij: f64| {
            let t1 = id.scale(nij);
            let t2 = ni.mul(dj).add(nj.mul(di)).mul(id2).neg();
            let t4 = n.mul(di.mul(dj)).mul(id3).scale(2.0);
            let t = t1.add(t2).add(t4);
            let t = if dij != 0.0 { t.add(n.mul(id2).scale(dij).neg()) } else { t };
            t.scale(2.0).widen(1e-13)
        };
        let hxx = hess(nxx, nx, nx, dx, dx, self.dxx);
        let hyy = hess(nyy, ny, ny, dy, dy, self.dyy);
        let hxy = hess(nxy, nx, ny, dx, dy, 0.0);
        // Value and gradient at the centre, with the magnitudes their rounding is relative to.
        let (wc, wcm) = (self.wc, self.wcm);
        let (sc, scm) = (wc.dot(vt), wcm.dot(vabs));
        let nc = wc.z * sc;
        let ncm = wcm.z * scm;
        let (dc, dxc, dyc) = (self.dc, self.dxc, self.dyc);
        let (nxc, nyc) = (a.z * sc + wc.z * av, bb.z * sc + wc.z * bv);
        let avm = a.abs().dot(vabs);
        let bvm = bb.abs().dot(vabs);
        let nxcm = a.z.abs() * scm + wcm.z * avm;
        let nycm = bb.z.abs() * scm + wcm.z * bvm;
        let fc = 2.0 * nc / dc;
        let fx = 2.0 * (nxc * dc - nc * dxc) / (dc * dc);
        let fy = 2.0 * (nyc * dc - nc * dyc) / (dc * dc);
        let fcm = 2.0 * ncm / dc;
        let fxm = 2.0 * (nxcm * dc + ncm * dxc.abs()) / (dc * dc);
        let fym = 2.0 * (nycm * dc + ncm * dyc.abs()) / (dc * dc);
        let fx_abs = fx.abs() + 1e-13 * fxm;
        let fy_abs = fy.abs() + 1e-13 * fym;
        let (mx, my) = (&self.mx, &self.my);
        let (px, py) = (mx.p, my.p);
        let pb = self.p;
        let lin = fx_abs * py * mx.m1 + fy_abs * px * my.m1;
        // ∫ H_xy(ζ)(x − c_x)(y − c_y) dP ≤ |h| |m1x m1y| + max|H_xy − h| ∫|x − c_x||y − c_y| dP for any h.
        let hxyc = 0.5 * (hxy.lo + hxy.hi);
        let dev = (hxy.hi - hxyc).max(hxyc - hxy.lo).max(0.0);
        let cross = hxyc.abs() * mx.m1 * my.m1 + dev * mx.mabs * my.mabs;
        let quad = |h: f64, pp: f64, s: &Side, upper: bool| {
            let m2 = if (h >= 0.0) == upper { s.m2_hi } else { s.m2_lo };
            0.5 * h * pp * m2
        };
        let qx_hi = quad(hxx.hi, py, mx, true);
        let qy_hi = quad(hyy.hi, px, my, true);
        let qx_lo = quad(hxx.lo, py, mx, false);
        let qy_lo = quad(hyy.lo, px, my, false);
        let base = pb * fc;
        let (xc, yc) = (self.xc, self.yc);
        let mag = pb * fcm
            + lin
            + cross
            + qx_hi.abs()
            + qy_hi.abs()
            + qx_lo.abs()
            + qy_lo.abs()
            + pb * (fxm + fym) * (1.0 + xc.abs() + yc.abs());
        let marg = REL2 * mag + 1e-300;
        let u = base + lin + cross + qx_hi + qy_hi + marg;
        let l = base - lin - cross + qx_lo + qy_lo - marg;
        // The pointwise range of F over the box from the same model.
        let (hx, hy) = (self.hx, self.hy);
        let hxy_abs = hxy.lo.abs().max(hxy.hi.abs());
        let lin_r = fx_abs * hx + fy_abs * hy;
        let f_hi = fc + lin_r + 0.5 * (hxx.hi.max(0.0) * hx * hx + hyy.hi.max(0.0) * hy * hy) + hxy_abs * hx * hy;
        let f_lo = fc - lin_r + 0.5 * (hxx.lo.min(0.0) * hx * hx + hyy.lo.min(0.0) * hy * hy) - hxy_abs * hx * hy;
        let mr = REL2
            * (fcm
                + lin_r
                + hxy_abs * hx * hy
                + (hxx.hi.abs() + hxx.lo.abs()) * hx * hx
                + (hyy.hi.abs() + hyy.lo.abs()) * hy * hy
                + 1.0);
        Second { u, l, f_hi: f_hi + mr, f_lo: f_lo - mr }
    }
}

/// The least squared distance from the origin to the convex quadrilateral `pq` (0 inside it).
fn min_distance2(pq: &[[f64; 2]; 4]) -> f64 {
    let mut inside_pos = true;
    let mut inside_neg = true;
    let mut best = f64::INFINITY;
    for k in 0..4 {
        let [px, py] = pq[k];
        let [qx, qy] = pq[(k + 1) % 4];
        let (ex, ey) = (qx - px, qy - py);
        let cross = ex * (-py) - ey * (-px);
        inside_pos &= cross >= 0.0;
        inside_neg &= cross <= 0.0;
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 { (-(px * ex + py * ey) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let (dx, dy) = (px + t * ex, py + t * ey);
        best = best.min(dx * dx + dy * dy);
    }
    if inside_pos || inside_neg {
        0.0
    } else {
        best
    }
}
