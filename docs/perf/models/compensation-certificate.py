"""Certified upper bound Ê(ω) >= E(ω) for the reciprocal Ward facet lobe albedo (Kulla-Conty): a
model of `src/brdf/compensation/bake.rs` with second-order box bounds (a Taylor model of f + 1 = 2N/D
with interval bounds of its Hessian, against the Gaussian's box moments) and nodes placed along the
kink lines of tilted lobes, in numpy. It prints, for one lobe, the white furnace at views up to 80°
and 89°, the least Ê − E over random views (against an independent quadrature of E), Ē and the box
evaluations taken.

    pip install numpy scipy
    python3 docs/perf/models/compensation-certificate.py ALPHA RATIO TILT_DEG SPLIT [N] [ETA] [C]
    python3 docs/perf/models/compensation-certificate.py 0.3 5 45 1 32 1e-4 4.5

Representation: bilinear table over the view slope V = (ωx/ωz, ωy/ωz) on a rectangular (non-uniform)
grid xs × ys; Ê = min(1, bilinear(v) + m_rt) inside the grid, Ê = 1 outside.

Why bilinear in V and not (θ,φ): for each facet h (world, h_z>0) g = clamp(f_h(V),0,1) with
f_h(V) = 2 h_z (h·(V,1)) − 1 AFFINE in V.  So per slope box b:
  e_b(V) = ∫_b clamp(f_h(V)) dP <= c0_b(V) − χ ℓ_b(V),  χ∈{0,1},
  c0_b(V) = ∫_b max(0,f_h(V)) dP   (convex in V),   ℓ_b(V) = ∫_b (f_h(V)−1) dP  (affine in V).
A convex function is <= the bilinear interpolant of its corner values on any axis-aligned rectangle,
an affine one equals it, so on a table cell C with corners n_i and bilinear weights λ_i:
  e_b(V) <= Σ λ_i w_{b,i},  w_{b,i} = P_b·max(0,S_b(n_i)) − χ P_b (I_b(n_i) − 1)
with S_b, I_b certified sup/inf of f over the box at the (fixed) corner view n_i; or w_{b,i}=P_b
(e_b<=P_b), or exact P_b / 0 when the box is saturated (I>=1 / S<=0) at all 4 corners.
Node value v_n = max over cells C ∋ n of Σ_b w_{b,n}(C)  (+ rounding margins).
"""
import numpy as np, time, sys, json
from scipy.special import ndtr, ndtri

# ======================= lobe model and independent reference =======================

def rotx(b):
    c, s = np.cos(b), np.sin(b)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])

class Lobe:
    """Ward facet lobe: alpha_x, alpha_y, tangent angle phi, tilt Q (3x3).
    w = M @ (X, Y, 1) is an (unnormalised) world half vector for standard-normal (X, Y)."""
    def __init__(self, ax, ay, phi=0.0, Q=None):
        self.ax, self.ay, self.phi = ax, ay, phi
        self.Q = np.eye(3) if Q is None else np.asarray(Q, float)
        c, s = np.cos(phi), np.sin(phi)
        sx, sy = ax / np.sqrt(2), ay / np.sqrt(2)
        # facet-frame h' ∝ (R(phi)(s_r, t_r), 1); s_r = sx X, t_r = sy Y
        A = np.array([[c * sx, -s * sy, 0], [s * sx, c * sy, 0], [0, 0, 1.0]])
        self.M = self.Q @ A

    def F(self, a, b):
        """brute-force BRDF, a, b (...,3) unit, world frame."""
        h = a + b
        hp = h @ self.Q  # Q^-1 h = Q^T h  (row vectors)
        c, s = np.cos(self.phi), np.sin(self.phi)
        hx = hp[..., 0] * c + hp[..., 1] * s
        hy = -hp[..., 0] * s + hp[..., 1] * c
        hz = hp[..., 2]
        ok = (hz > 0) & (a[..., 2] >= 2.0 ** -20) & (b[..., 2] >= 2.0 ** -20)
        hzs = np.where(ok, hz, 1.0)
        sl, tl = hx / hzs, hy / hzs
        e = (sl / self.ax) ** 2 + (tl / self.ay) ** 2
        mz = np.maximum(a[..., 2], b[..., 2])
        val = np.exp(-e) * (1 + sl * sl + tl * tl) / (2 * np.pi * self.ax * self.ay * hzs * mz)
        return np.where(ok, val, 0.0)

def gfun(w, wo):
    """g for unnormalised half vectors w (...,3) and view wo (3,) or broadcastable."""
    dot = (w * wo).sum(-1)
    n2 = (w * w).sum(-1)
    f = 2 * np.maximum(dot, 0) * w[..., 2] / (n2 * wo[..., 2]) - 1
    return np.clip(f, 0, 1)

def view(theta, phi):
    theta, phi = np.broadcast_arrays(theta, phi)
    st = np.sin(theta)
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], -1)

class RefE:
    """E by probit-midpoint quadrature, n x n."""
    def __init__(self, lobe, n=512):
        a = (np.arange(n) + 0.5) / n
        x = ndtri(a)
        X, Y = np.meshgrid(x, x, indexing='ij')
        P = np.stack([X.ravel(), Y.ravel(), np.ones(n * n)], -1)
        self.w = P @ lobe.M.T
        self.w /= np.linalg.norm(self.w, axis=-1, keepdims=True)
        self.n = n
    def __call__(self, wos):
        wos = np.atleast_2d(wos)
        out = np.empty(len(wos))
        w = self.w
        for i, wo in enumerate(wos):
            dot = w @ wo
            f = 2 * np.maximum(dot, 0) * w[:, 2] / wo[2] - 1
            out[i] = np.clip(f, 0, 1).mean()
        return out

class RefE2(RefE):
    """E by uniform midpoint in (X, Y) on [-L, L]^2 with Gaussian weights (O(h^2) even across kinks)."""
    def __init__(self, lobe, n=600, L=8.0):
        x = (np.arange(n) + 0.5) / n * 2 * L - L
        wt = np.exp(-x * x / 2) / np.sqrt(2 * np.pi) * (2 * L / n)
        X, Y = np.meshgrid(x, x, indexing='ij')
        W = np.outer(wt, wt).ravel()
        keep = W > 1e-17
        P = np.stack([X.ravel()[keep], Y.ravel()[keep], np.ones(keep.sum())], -1)
        self.w = P @ lobe.M.T
        self.w /= np.linalg.norm(self.w, axis=-1, keepdims=True)
        self.wt = W[keep]
    def __call__(self, wos):
        wos = np.atleast_2d(wos)
        out = np.empty(len(wos))
        w = self.w
        for i, wo in enumerate(wos):
            f = 2 * np.maximum(w @ wo, 0) * w[:, 2] / wo[2] - 1
            out[i] = np.clip(f, 0, 1) @ self.wt
        return out
def Vview(Vx, Vy):
    w = np.stack([Vx, Vy, np.ones_like(Vx)], -1)
    return w / np.linalg.norm(w, axis=-1, keepdims=True)

# ======================= certification =======================


ERR_MODE = 'lower'
VIEW_STOP = True
KINK_OFFSETS = (-3, -1.5, -0.5, 0, 0.5, 1.5, 3)   # kink nodes, in units of α·sqrt(1+k²)
VIEW_RATIO = 0.6
EPS_REL = 1e-12     # margin on every certified f bound, relative to the magnitude of the terms

def box_prob(a, b):
    """Φ(b) − Φ(a) without cancellation in the upper tail (a <= b)."""
    up = a > 0
    return np.where(up, ndtr(-a) - ndtr(-b), ndtr(b) - ndtr(a))

def quad_data(M, x0, x1, y0, y1):
    """world-slope quad of a standardized slope box: vertices (P,Q) (n,4), status, rmin2, rmax2.
    status: 1 regular (w_z>0 on box), 0 w_z<=0 on whole box (g=0), -1 pole inside (unbounded)."""
    X = np.stack([x0, x1, x1, x0], -1); Y = np.stack([y0, y0, y1, y1], -1)
    wx = M[0, 0] * X + M[0, 1] * Y + M[0, 2]
    wy = M[1, 0] * X + M[1, 1] * Y + M[1, 2]
    wz = M[2, 0] * X + M[2, 1] * Y + M[2, 2]
    mag = np.abs(wx) + np.abs(wy) + np.abs(wz)
    tol = 1e-12 * mag
    status = np.where((wz > tol).all(-1), 1, np.where((wz < -tol).all(-1), 0, -1))
    wzs = np.where(status[:, None] == 1, wz, 1.0)
    P = wx / wzs; Q = wy / wzs
    r2 = P * P + Q * Q
    rmax2 = r2.max(-1)
    # exact min |.|^2 over the convex quad: 0 if origin inside, else min distance to edges
    P1 = np.roll(P, -1, -1); Q1 = np.roll(Q, -1, -1)
    ex, ey = P1 - P, Q1 - Q
    cross = ex * (-Q) - ey * (-P)
    inside = (cross >= 0).all(-1) | (cross <= 0).all(-1)
    L2 = ex * ex + ey * ey
    t = np.clip(-(P * ex + Q * ey) / np.where(L2 > 0, L2, 1), 0, 1)
    dx, dy = P + t * ex, Q + t * ey
    rmin2 = np.where(inside, 0.0, (dx * dx + dy * dy).min(-1))
    # rounding: shrink rmin2, grow rmax2
    rmin2 = np.maximum(0.0, rmin2 * (1 - 1e-10) - 1e-12 * (1 + rmax2))
    rmax2 = rmax2 * (1 + 1e-10) + 1e-12
    return P, Q, status, rmin2, rmax2

def f_bounds(P, Q, rmin2, rmax2, Vx, Vy):
    """certified sup and inf of f_h(V) = 2(1 + P Vx + Q Vy)/(1+P²+Q²) − 1 over a quad, at view V.
    P, Q (n,4); Vx, Vy (n,) or scalars."""
    num = 1 + P * Vx[..., None] + Q * Vy[..., None]
    nmax, nmin = num.max(-1), num.min(-1)
    dmin, dmax = 1 + rmin2, 1 + rmax2
    S = 2 * np.where(nmax >= 0, nmax / dmin, nmax / dmax) - 1
    I = 2 * np.where(nmin >= 0, nmin / dmax, nmin / dmin) - 1
    mag = 1 + (np.abs(P) + np.abs(Q)).max(-1) * (1 + np.abs(Vx) + np.abs(Vy))
    m = EPS_REL * 8 * mag
    return S + m, I - m

def f_point(M, X, Y, Vx, Vy):
    w = np.stack([M[0, 0] * X + M[0, 1] * Y + M[0, 2], M[1, 0] * X + M[1, 1] * Y + M[1, 2],
                  M[2, 0] * X + M[2, 1] * Y + M[2, 2]], -1)
    n2 = (w * w).sum(-1)
    f = 2 * w[..., 2] * (w[..., 0] * Vx + w[..., 1] * Vy + w[..., 2]) / n2 - 1
    return np.where(w[..., 2] > 0, np.clip(f, 0, 1), 0.0)

def cell_weights(M, x0, x1, y0, y1, cVx, cVy):
    """per (box, cell) items: cVx, cVy (n,4) corner views of the item's cell.
    returns w (n,4) (certified per-corner weights), err (n,) estimated slack, P."""
    Pb = box_prob(x0, x1) * box_prob(y0, y1)
    P, Q, st, rmin2, rmax2 = quad_data(M, x0, x1, y0, y1)
    S = np.empty_like(cVx); I = np.empty_like(cVx)
    for i in range(4):
        S[:, i], I[:, i] = f_bounds(P, Q, rmin2, rmax2, cVx[:, i], cVy[:, i])
    Pc = Pb[:, None]
    optA = np.broadcast_to(Pc, S.shape)
    optB = Pc * np.maximum(0, S)
    optC = Pc * (np.maximum(0, S) + 1 - I)
    sA, sB, sC = optA.sum(-1), optB.sum(-1), optC.sum(-1)
    w = np.where((sB <= sA)[:, None] & (sB <= sC)[:, None], optB, np.where((sC <= sA)[:, None], optC, optA))
    sat1 = (I >= 1).all(-1); sat0 = (S <= 0).all(-1)
    w = np.where(sat1[:, None], Pc, w)
    w = np.where(sat0[:, None], 0.0, w)
    w = np.where((st == 1)[:, None], w, np.where((st == 0)[:, None], 0.0, optA))
    # estimated slack: w minus P * g at the box centre facet at each corner view
    if ERR_MODE == 'centre':
        xc, yc = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        g = np.stack([f_point(M, xc, yc, cVx[:, i], cVy[:, i]) for i in range(4)], -1)
    else:   # certified lower bound of g on the box: gap = upper - lower >= true slack
        g = np.where((st == 1)[:, None], np.clip(I, 0, 1), 0.0)
    err = (w - Pc * g).max(-1)
    return w, err, Pb

def certify(lobe, xs, ys, eta, L=8.0, max_rounds=30, chunk=48, verbose=False, order=2):
    """node values v (len(xs), len(ys)) with bilinear(v) >= E on every cell; stats."""
    M = lobe.M
    nx, ny = len(xs) - 1, len(ys) - 1
    W = np.zeros((nx, ny, 4))
    edges = np.array([-L, -2, -1, 0, 1, 2, L])
    e0, e1 = np.meshgrid(np.arange(6), np.arange(6), indexing='ij')
    bx0, bx1 = edges[e0.ravel()], edges[e0.ravel() + 1]
    by0, by1 = edges[e1.ravel()], edges[e1.ravel() + 1]
    cells = [(i, j) for i in range(nx) for j in range(ny)]
    n_eval = 0; n_leaf = 0; n_items_max = 0
    for k in range(0, len(cells), chunk):
        cc = np.array(cells[k:k + chunk])
        nc = len(cc)
        cid = np.repeat(np.arange(nc), len(bx0))
        X0, X1 = np.tile(bx0, nc), np.tile(bx1, nc)
        Y0, Y1 = np.tile(by0, nc), np.tile(by1, nc)
        cx = np.stack([xs[cc[:, 0]], xs[cc[:, 0] + 1], xs[cc[:, 0]], xs[cc[:, 0] + 1]], -1)
        cy = np.stack([ys[cc[:, 1]], ys[cc[:, 1]], ys[cc[:, 1] + 1], ys[cc[:, 1] + 1]], -1)
        acc = np.zeros((nc, 4)); nb = np.zeros(nc)
        perr_v = None
        for r in range(max_rounds):
            if len(cid) == 0:
                break
            cw = cell_weights if order == 1 else cell_weights2
            w, err, Pb = cw(M, X0, X1, Y0, Y1, cx[cid], cy[cid])
            n_eval += len(cid)
            if order == 1:
                split = err > eta
                err_v = None
            else:
                err, err_sp = err
                err_v = np.maximum(0, err - err_sp)
                if perr_v is None or not VIEW_STOP:
                    vflag = np.ones(len(cid), bool)
                else:   # splitting helped the view-straddle part of the parent?
                    ns = len(cid) // 4
                    sib = err_v.reshape(4, ns).sum(0)
                    vflag = np.tile(sib < VIEW_RATIO * perr_v, 4)
                split = (err_sp > eta) | ((err_v > eta) & vflag)
            split &= (r < max_rounds - 1)
            keep = ~split
            np.add.at(acc, cid[keep], w[keep])
            np.add.at(nb, cid[keep], 1)
            if err_v is not None:
                perr_v = err_v[split]
            cid, X0, X1, Y0, Y1 = cid[split], X0[split], X1[split], Y0[split], Y1[split]
            xm, ym = 0.5 * (X0 + X1), 0.5 * (Y0 + Y1)
            cid = np.tile(cid, 4)
            X0, X1 = np.concatenate([X0, xm, X0, xm]), np.concatenate([xm, X1, xm, X1])
            Y0, Y1 = np.concatenate([Y0, Y0, ym, ym]), np.concatenate([ym, ym, Y1, Y1])
            n_items_max = max(n_items_max, len(cid))
        tail = 4 * ndtr(-L)               # >= mass outside [-L,L]^2, counted with g = 1
        acc += tail
        acc += 1e-13 * nb[:, None] + 1e-12   # rounding of box probabilities and of the sum
        W[cc[:, 0], cc[:, 1]] = acc
        n_leaf += nb.sum()
    v = np.full((nx + 1, ny + 1), -np.inf)
    # corner order: (i,j), (i+1,j), (i,j+1), (i+1,j+1)
    for c, (di, dj) in enumerate([(0, 0), (1, 0), (0, 1), (1, 1)]):
        v[di:nx + di, dj:ny + dj] = np.maximum(v[di:nx + di, dj:ny + dj], W[:, :, c])
    return v, dict(evals=n_eval, leaves=n_leaf, cells=nx * ny, leaves_per_cell=n_leaf / (nx * ny))

# ---------------- grids ----------------
def axis_nodes(N, vmax, c, kinks=()):
    sm = vmax / (c + vmax)
    s = np.linspace(-sm, sm, N + 1)
    x = c * s / (1 - np.abs(s))
    if len(kinks):
        sk = np.array([k / (c + abs(k)) for k in kinks if abs(k) < vmax])
        ds = s[1] - s[0]
        if len(sk):
            far = np.abs(s[:, None] - sk[None, :]).min(-1) > 0.4 * ds
            far[0] = far[-1] = True
            x = np.sort(np.concatenate([x[far], sk / (1 - np.abs(sk)) * c]))
    return np.unique(x.astype(np.float32).astype(np.float64))   # nodes exactly representable in f32

def tilt_kinks(lobe_list, width=2.0):
    """kink lines of the mean normals plus two nodes at ± width·α·sqrt(1+k²) (the kinks are smoothed
    over ~α|Ṽ| by the facet spread)."""
    ks = _tilt_kinks(lobe_list)
    if width <= 0 or not ks:
        return ks
    a = max(max(Lb.ax, Lb.ay) for Lb in lobe_list)
    return [k + d * a * np.sqrt(1 + k * k) for k in ks for d in KINK_OFFSETS]

def _tilt_kinks(lobe_list):
    """Vy of the kink lines f_m(V) = 0, 1 of the mean facet normals (tilt about x: m_x = 0)."""
    ks = []
    for Lb in lobe_list:
        m = Lb.Q[:, 2]
        if abs(m[1]) < 1e-9:
            continue
        for c in (0.0, 1.0):
            ks.append(((c + 1) / (2 * m[2]) - m[2]) / m[1])
    return ks

# ---------------- evaluation (runtime emulation, f32) ----------------
M_RT = np.float32(2.0 ** -14)      # runtime margin: f32 view slope, rotation & interpolation rounding (E is 1-Lipschitz in V, |V|<=57)
class Table:
    def __init__(self, xs, ys, v):
        self.xs = xs.astype(np.float32); self.ys = ys.astype(np.float32)
        v = np.where(np.isfinite(v), v, 1.0)
        # store rounded up to f32
        vf = v.astype(np.float32)
        vf = np.where(vf.astype(np.float64) < v, np.nextafter(vf, np.float32(np.inf)), vf)
        self.v = vf
    def __call__(self, wo):
        wo = np.asarray(wo, np.float32)
        Vx = wo[:, 0] / wo[:, 2]; Vy = wo[:, 1] / wo[:, 2]
        out = np.ones(len(wo), np.float32)
        xs, ys = self.xs, self.ys
        ok = (Vx >= xs[0]) & (Vx <= xs[-1]) & (Vy >= ys[0]) & (Vy <= ys[-1]) & (wo[:, 2] > 0)
        i = np.clip(np.searchsorted(xs, Vx, 'right') - 1, 0, len(xs) - 2)
        j = np.clip(np.searchsorted(ys, Vy, 'right') - 1, 0, len(ys) - 2)
        a = np.clip((Vx - xs[i]) / (xs[i + 1] - xs[i]), 0, 1).astype(np.float32)
        b = np.clip((Vy - ys[j]) / (ys[j + 1] - ys[j]), 0, 1).astype(np.float32)
        one = np.float32(1)
        val = ((one - a) * ((one - b) * self.v[i, j] + b * self.v[i, j + 1])
               + a * ((one - b) * self.v[i + 1, j] + b * self.v[i + 1, j + 1]))
        val = np.minimum(one, val + M_RT)
        return np.where(ok, val, out)

def rect_weight(x0, x1, y0, y1):
    """exact ∫∫ dx dy / (1+x²+y²)² over a rectangle (cosθ dω in view-slope coordinates)."""
    def F(a, b):
        sa, sb = np.sqrt(1 + a * a), np.sqrt(1 + b * b)
        return 0.5 * (a / sa * np.arctan(b / sa) + b / sb * np.arctan(a / sb))
    return F(x1, y1) - F(x0, y1) - F(x1, y0) + F(x0, y0)

def ebar_lower(tab, sub=6):
    """lower bound of (1/π)∫ Ê cosθ dω for Ê >= min(1, bilinear(v)) inside, = 1 outside."""
    xs = tab.xs.astype(np.float64); ys = tab.ys.astype(np.float64); v = tab.v.astype(np.float64)
    t = np.linspace(0, 1, sub + 1)
    deficit = 0.0
    for i in range(len(xs) - 1):
        gx = xs[i] + t * (xs[i + 1] - xs[i])
        for j in range(len(ys) - 1):
            gy = ys[j] + t * (ys[j + 1] - ys[j])
            A, B = np.meshgrid(t, t, indexing='ij')
            val = ((1 - A) * (1 - B) * v[i, j] + A * (1 - B) * v[i + 1, j] + (1 - A) * B * v[i, j + 1] + A * B * v[i + 1, j + 1])
            d = 1 - np.minimum(1, val)                  # deficit at sub-grid points
            dmax = np.maximum(np.maximum(d[:-1, :-1], d[1:, :-1]), np.maximum(d[:-1, 1:], d[1:, 1:]))
            wgt = rect_weight(gx[:-1, None], gx[1:, None], gy[None, :-1], gy[None, 1:])
            deficit += (dmax * wgt).sum()
    return 1 - deficit / np.pi * (1 + 1e-9) - 1e-9

def ebar_accurate(tab, n=400000, rng=np.random.default_rng(5)):
    """Monte Carlo estimate of the cosine-weighted mean of Ê (for reporting the bound's tightness)."""
    u1, u2 = rng.random(n), rng.random(n)
    r = np.sqrt(u1); ph = 2 * np.pi * u2
    wo = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(1 - u1)], -1)
    return tab(wo).astype(np.float64).mean()


def certify_budget(lobe, xs, ys, tau, L=8.0, max_rounds=40, chunk=64, frac=0.3, init=None):
    """Per-cell greedy refinement: split the boxes with the largest (splittable) gap until the
    cell's summed gap estimate <= tau.  Returns v (node values) and stats."""
    M = lobe.M
    nx, ny = len(xs) - 1, len(ys) - 1
    W = np.zeros((nx, ny, 4))
    edges = np.array([-L, -2, -1, 0, 1, 2, L]) if init is None else init
    ne = len(edges) - 1
    e0, e1 = np.meshgrid(np.arange(ne), np.arange(ne), indexing='ij')
    bx0, bx1 = edges[e0.ravel()], edges[e0.ravel() + 1]
    by0, by1 = edges[e1.ravel()], edges[e1.ravel() + 1]
    cells = [(i, j) for i in range(nx) for j in range(ny)]
    n_eval = 0; n_leaf = 0
    for k in range(0, len(cells), chunk):
        cc = np.array(cells[k:k + chunk]); nc = len(cc)
        cx = np.stack([xs[cc[:, 0]], xs[cc[:, 0] + 1], xs[cc[:, 0]], xs[cc[:, 0] + 1]], -1)
        cy = np.stack([ys[cc[:, 1]], ys[cc[:, 1]], ys[cc[:, 1] + 1], ys[cc[:, 1] + 1]], -1)
        cid = np.repeat(np.arange(nc), len(bx0))
        X0, X1 = np.tile(bx0, nc), np.tile(bx1, nc); Y0, Y1 = np.tile(by0, nc), np.tile(by1, nc)
        w, (err, esp), _ = cell_weights2(M, X0, X1, Y0, Y1, cx[cid], cy[cid]); n_eval += len(cid)
        ev = np.maximum(0, err - esp); es = esp + ev     # all splittable initially
        for r in range(max_rounds):
            tot = np.bincount(cid, es, nc)
            mx = np.zeros(nc); np.maximum.at(mx, cid, es)
            act = tot > tau
            if not act.any():
                break
            split = act[cid] & (es >= frac * mx[cid]) & (es > 0)
            if not split.any():
                break
            pe_v = ev[split]
            c_s, a0, a1, b0, b1 = cid[split], X0[split], X1[split], Y0[split], Y1[split]
            keep = ~split
            cid, X0, X1, Y0, Y1, w, ev, es = (cid[keep], X0[keep], X1[keep], Y0[keep], Y1[keep],
                                              w[keep], ev[keep], es[keep])
            am, bm = 0.5 * (a0 + a1), 0.5 * (b0 + b1)
            nc_ = np.tile(c_s, 4)
            n0, n1 = np.concatenate([a0, am, a0, am]), np.concatenate([am, a1, am, a1])
            m0, m1 = np.concatenate([b0, b0, bm, bm]), np.concatenate([bm, bm, b1, b1])
            wn, (errn, espn), _ = cell_weights2(M, n0, n1, m0, m1, cx[nc_], cy[nc_]); n_eval += len(nc_)
            evn = np.maximum(0, errn - espn)
            ns = len(c_s)
            vflag = np.tile(evn.reshape(4, ns).sum(0) < VIEW_RATIO * pe_v, 4)
            esn = espn + np.where(vflag, evn, 0)
            cid = np.concatenate([cid, nc_]); X0 = np.concatenate([X0, n0]); X1 = np.concatenate([X1, n1])
            Y0 = np.concatenate([Y0, m0]); Y1 = np.concatenate([Y1, m1]); w = np.concatenate([w, wn])
            ev = np.concatenate([ev, evn]); es = np.concatenate([es, esn])
        acc = np.zeros((nc, 4)); np.add.at(acc, cid, w)
        nb = np.bincount(cid, minlength=nc)
        acc += 4 * ndtr(-L) + 1e-13 * nb[:, None] + 1e-12
        W[cc[:, 0], cc[:, 1]] = acc
        n_leaf += len(cid)
    v = np.full((nx + 1, ny + 1), -np.inf)
    for c, (di, dj) in enumerate([(0, 0), (1, 0), (0, 1), (1, 1)]):
        v[di:nx + di, dj:ny + dj] = np.maximum(v[di:nx + di, dj:ny + dj], W[:, :, c])
    return v, dict(evals=n_eval, leaves=n_leaf, cells=nx * ny, leaves_per_cell=n_leaf / (nx * ny))

def _Fw(a, b):
    """antiderivatives G_ij with ∂²G/∂x∂y = x^i y^j / (1+x²+y²)²."""
    sa, sb = np.sqrt(1 + a * a), np.sqrt(1 + b * b)
    F00 = 0.5 * (a / sa * np.arctan(b / sa) + b / sb * np.arctan(a / sb))
    F10 = -np.arctan(b / sa) / (2 * sa)
    F01 = -np.arctan(a / sb) / (2 * sb)
    F11 = -0.25 * np.log1p(a * a + b * b)
    return np.stack([F00, F10, F01, F11])

def ebar_lower2(tab, sub=8):
    """lower bound of Ē: exact ∫ bilinear·w on cells whose 4 nodes are <= 1 (there min(1,B) = B),
    sub-rectangle corner-min bound elsewhere; Ê = 1 outside the table."""
    xs = tab.xs.astype(np.float64); ys = tab.ys.astype(np.float64); v = tab.v.astype(np.float64)
    X0, Y0 = np.meshgrid(xs[:-1], ys[:-1], indexing='ij'); X1, Y1 = np.meshgrid(xs[1:], ys[1:], indexing='ij')
    v00, v10, v01, v11 = v[:-1, :-1], v[1:, :-1], v[:-1, 1:], v[1:, 1:]
    hx, hy = X1 - X0, Y1 - Y0
    # B = c0 + cx x + cy y + cxy x y in global coordinates
    cxy = (v11 - v10 - v01 + v00) / (hx * hy)
    cx = (v10 - v00) / hx - cxy * Y0
    cy = (v01 - v00) / hy - cxy * X0
    c0 = v00 - cx * X0 - cy * Y0 - cxy * X0 * Y0
    G = _Fw(X1, Y1) - _Fw(X0, Y1) - _Fw(X1, Y0) + _Fw(X0, Y0)
    intB = c0 * G[0] + cx * G[1] + cy * G[2] + cxy * G[3]
    mag = np.abs(c0 * G[0]) + np.abs(cx * G[1]) + np.abs(cy * G[2]) + np.abs(cxy * G[3])
    wgt = rect_weight(X0, X1, Y0, Y1)
    deficit_exact = wgt - intB + 1e-10 * mag + 1e-14
    ok = np.maximum(np.maximum(v00, v10), np.maximum(v01, v11)) <= 1
    deficit = np.where(ok, np.maximum(deficit_exact, 0), 0.0).sum()
    t = np.linspace(0, 1, sub + 1)
    A, B = np.meshgrid(t, t, indexing='ij')
    for i, j in zip(*np.nonzero(~ok)):
        gx = xs[i] + t * (xs[i + 1] - xs[i]); gy = ys[j] + t * (ys[j + 1] - ys[j])
        val = ((1 - A) * (1 - B) * v[i, j] + A * (1 - B) * v[i + 1, j] + (1 - A) * B * v[i, j + 1] + A * B * v[i + 1, j + 1])
        d = 1 - np.minimum(1, val)
        dmax = np.maximum(np.maximum(d[:-1, :-1], d[1:, :-1]), np.maximum(d[:-1, 1:], d[1:, 1:]))
        deficit += (dmax * rect_weight(gx[:-1, None], gx[1:, None], gy[None, :-1], gy[None, 1:])).sum()
    return 1 - deficit / np.pi * (1 + 1e-9) - 1e-9

# ---------------- 1D table (isotropic, untilted: E depends on |V| only) ----------------
class Table1D:
    def __init__(self, rs, v):
        self.rs = rs.astype(np.float32)
        vf = v.astype(np.float32)
        self.v = np.where(vf.astype(np.float64) < v, np.nextafter(vf, np.float32(np.inf)), vf)
    def __call__(self, wo):
        wo = np.asarray(wo, np.float32)
        r = np.sqrt(wo[:, 0] ** 2 + wo[:, 1] ** 2) / wo[:, 2]
        ok = (r <= self.rs[-1]) & (wo[:, 2] > 0)
        i = np.clip(np.searchsorted(self.rs, r, 'right') - 1, 0, len(self.rs) - 2)
        a = np.clip((r - self.rs[i]) / (self.rs[i + 1] - self.rs[i]), 0, 1).astype(np.float32)
        val = (np.float32(1) - a) * self.v[i] + a * self.v[i + 1]
        return np.where(ok, np.minimum(np.float32(1), val + M_RT), np.float32(1))

def ebar_lower_1d(tab):
    """Ē >= 1 - (2/π)... exact: cosθ dω = 2π r dr/(1+r²)² ; lower bound with per-segment max deficit
    refined 64x (1D, cheap)."""
    rs = tab.rs.astype(np.float64); v = tab.v.astype(np.float64)
    deficit = 0.0
    t = np.linspace(0, 1, 65)
    for i in range(len(rs) - 1):
        r = rs[i] + t * (rs[i + 1] - rs[i])
        d = 1 - np.minimum(1, (1 - t) * v[i] + t * v[i + 1])
        dm = np.maximum(d[:-1], d[1:])
        W = 1 / (1 + r[:-1] ** 2) - 1 / (1 + r[1:] ** 2)     # ∫ 2 r dr/(1+r²)² over the piece = (1/π)∫cos dω
        deficit += (dm * W).sum()
    return 1 - deficit * (1 + 1e-9) - 1e-9

def rotz(g):
    c, s = np.cos(g), np.sin(g)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])

# ======================= second-order box bounds =======================
SQ2PI = np.sqrt(2 * np.pi)
TAYLOR_RANGE = True
def phi(x): return np.exp(-0.5 * x * x) / SQ2PI

# interval helpers (lo, hi)
def imul(a, b):
    p = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    return p.min(0), p.max(0)
def iadd(*xs): return sum(x[0] for x in xs), sum(x[1] for x in xs)
def ineg(a): return -a[1], -a[0]
def iconst(c): return c, c
def isq(a):
    lo = np.where((a[0] <= 0) & (a[1] >= 0), 0.0, np.minimum(a[0] ** 2, a[1] ** 2))
    return lo, np.maximum(a[0] ** 2, a[1] ** 2)
def iscal(c, a):  # scalar array times interval
    return np.minimum(c * a[0], c * a[1]), np.maximum(c * a[0], c * a[1])
def ilin(v):  # interval of a linear function from its 4 corner values (n,4)
    return v.min(-1), v.max(-1)

def moments_1d(x0, x1):
    """bounds for box side [x0,x1]: P, (m2_lo, m2_hi) of ∫(x-c)^2 φ, |m1| bound of ∫(x-c) φ, mabs of ∫|x-c| φ."""
    d = x1 - x0
    xn = np.clip(0.0, x0, x1)
    pmax = phi(xn); pmin = np.minimum(phi(x0), phi(x1))
    # sup |x| φ(x) on [x0,x1]: endpoints and |x| = 1
    cand = np.maximum(np.abs(x0) * phi(x0), np.abs(x1) * phi(x1))
    one_in = ((x0 <= 1) & (x1 >= 1)) | ((x0 <= -1) & (x1 >= -1))
    dphi = np.where(one_in, phi(1.0), cand)
    k = d ** 3 / 12
    return pmin * k, pmax * k, dphi * k, pmax * d * d / 4

def dmin_exact(M, x0, x1, y0, y1, Dc):
    """exact min over the box of |w0 + X a + Y b|^2 (convex quadratic). Dc: corner values (n,4)."""
    a, b, w0 = M[:, 0], M[:, 1], M[:, 2]
    G = np.array([[a @ a, a @ b], [a @ b, b @ b]])
    r = -np.array([a @ w0, b @ w0])
    X, Y = np.linalg.solve(G, r)
    inside = (x0 <= X) & (X <= x1) & (y0 <= Y) & (Y <= y1)
    unc = np.sum((w0 + X * a + Y * b) ** 2)
    best = Dc.min(-1)
    # edges X = x0, x1 (minimise over Y in [y0,y1]); Y = y0, y1
    def line(Xf, ylo, yhi, u, v):  # min over t in [ylo,yhi] of |p + t v|^2 with p = w0 + Xf u
        p = w0[None, :] + Xf[:, None] * u[None, :]
        t = np.clip(-(p @ v) / (v @ v), ylo, yhi)
        q = p + t[:, None] * v[None, :]
        return (q * q).sum(-1)
    for Xf in (x0, x1):
        best = np.minimum(best, line(Xf, y0, y1, a, b))
    for Yf in (y0, y1):
        best = np.minimum(best, line(Yf, x0, x1, b, a))
    return np.where(inside, np.minimum(best, unc), best)

def second_order(M, x0, x1, y0, y1, Vx, Vy, Pb, mom):
    """upper and lower bounds of ∫_box (f_h(V) + 1) dP, f+1 = 2 w_z (w·Ṽ)/|w|^2, for one view per item.
    valid where w_z > 0 on the box (caller ensures)."""
    a, b, w0 = M[:, 0], M[:, 1], M[:, 2]
    (m2x_lo, m2x_hi, m1x, mabx), (m2y_lo, m2y_hi, m1y, maby), Px, Py, Dint = mom
    # corner values of linear functions
    X = np.stack([x0, x1, x1, x0], -1); Y = np.stack([y0, y0, y1, y1], -1)
    wz = w0[2] + X * a[2] + Y * b[2]
    s = (w0[0] * Vx + w0[1] * Vy + w0[2])[..., None] + X * (a[0] * Vx + a[1] * Vy + a[2])[..., None] \
        + Y * (b[0] * Vx + b[1] * Vy + b[2])[..., None]
    aw = (a @ w0) + X * (a @ a) + Y * (a @ b)
    bw = (b @ w0) + X * (a @ b) + Y * (b @ b)
    aV = a[0] * Vx + a[1] * Vy + a[2]; bV = b[0] * Vx + b[1] * Vy + b[2]
    WZ, S_, AW, BW = ilin(wz), ilin(s), ilin(aw), ilin(bw)
    N = imul(WZ, S_)
    NX = iadd(iscal(a[2], S_), iscal(aV, WZ)); NY = iadd(iscal(b[2], S_), iscal(bV, WZ))
    NXX = 2 * a[2] * aV; NYY = 2 * b[2] * bV; NXY = a[2] * bV + b[2] * aV
    DX = iscal(2.0, AW); DY = iscal(2.0, BW)
    DXX = 2 * (a @ a); DYY = 2 * (b @ b); DXY = 2 * (a @ b)
    iD = (1 / Dint[1], 1 / Dint[0]); iD2 = isq(iD); iD3 = imul(iD2, iD)
    def H(Nij, Ni, Nj, Di, Dj, Dij):
        t1 = iscal(Nij, iD)
        t2 = ineg(imul(iadd(imul(Ni, Dj), imul(Nj, Di)), iD2))
        t3 = ineg(iscal(Dij, imul(N, iD2)))
        t4 = iscal(2.0, imul(imul(N, imul(Di, Dj)), iD3))
        return iscal(2.0, iadd(t1, t2, t3, t4))
    Hxx = H(NXX, NX, NX, DX, DX, DXX); Hyy = H(NYY, NY, NY, DY, DY, DYY); Hxy = H(NXY, NX, NY, DX, DY, DXY)
    # centre value and gradient of F = f + 1 = 2N/D
    xc, yc = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    w = w0[None, :] + xc[:, None] * a[None, :] + yc[:, None] * b[None, :]
    sc = w[:, 0] * Vx + w[:, 1] * Vy + w[:, 2]
    Nc = w[:, 2] * sc; Dc = (w * w).sum(-1)
    NXc = a[2] * sc + w[:, 2] * aV; NYc = b[2] * sc + w[:, 2] * bV
    DXc = 2 * (w @ a); DYc = 2 * (w @ b)
    Fc = 2 * Nc / Dc
    FX = 2 * (NXc * Dc - Nc * DXc) / Dc ** 2; FY = 2 * (NYc * Dc - Nc * DYc) / Dc ** 2
    lin = np.abs(FX) * Py * m1x + np.abs(FY) * Px * m1y
    # cross term: ∫ H_xy(ξ)(x-cx)(y-cy) dP <= |H_xy(c)| |m1x m1y| + dev(H_xy) ∫|x-cx||y-cy| dP
    NXYc = NXY; DXYc = DXY
    Hxyc = 2 * (NXYc / Dc - (NXc * DYc + NYc * DXc) / Dc ** 2 - Nc * DXYc / Dc ** 2 + 2 * Nc * DXc * DYc / Dc ** 3)
    dev = np.maximum(Hxy[1] - Hxyc, Hxyc - Hxy[0])
    dev = np.maximum(dev, 0) + 1e-9 * np.abs(Hxyc)
    cross = np.abs(Hxyc) * m1x * m1y + dev * mabx * maby
    qx_hi = 0.5 * np.where(Hxx[1] >= 0, Hxx[1] * Py * m2x_hi, Hxx[1] * Py * m2x_lo)
    qy_hi = 0.5 * np.where(Hyy[1] >= 0, Hyy[1] * Px * m2y_hi, Hyy[1] * Px * m2y_lo)
    qx_lo = 0.5 * np.where(Hxx[0] >= 0, Hxx[0] * Py * m2x_lo, Hxx[0] * Py * m2x_hi)
    qy_lo = 0.5 * np.where(Hyy[0] >= 0, Hyy[0] * Px * m2y_lo, Hyy[0] * Px * m2y_hi)
    base = Pb * Fc
    mag = (np.abs(base) + lin + cross + np.abs(qx_hi) + np.abs(qy_hi) + np.abs(qx_lo) + np.abs(qy_lo)
           + Pb * (1 + np.abs(FX) + np.abs(FY)) * (1 + np.abs(xc) + np.abs(yc)))
    marg = 1e-11 * mag
    U = base + lin + cross + qx_hi + qy_hi + marg
    L = base - lin - cross + qx_lo + qy_lo - marg
    # pointwise range of F over the box from the Taylor model (first-order tight)
    dx, dy = 0.5 * (x1 - x0), 0.5 * (y1 - y0)
    Hxy_abs = np.maximum(np.abs(Hxy[0]), np.abs(Hxy[1]))
    lin_r = np.abs(FX) * dx + np.abs(FY) * dy
    Fhi = Fc + lin_r + 0.5 * (np.maximum(Hxx[1], 0) * dx * dx + np.maximum(Hyy[1], 0) * dy * dy) + Hxy_abs * dx * dy
    Flo = Fc - lin_r + 0.5 * (np.minimum(Hxx[0], 0) * dx * dx + np.minimum(Hyy[0], 0) * dy * dy) - Hxy_abs * dx * dy
    mr = 1e-11 * (np.abs(Fc) + lin_r + Hxy_abs * dx * dy + np.abs(Hxx[1]) * dx * dx + np.abs(Hyy[1]) * dy * dy
                  + np.abs(Hxx[0]) * dx * dx + np.abs(Hyy[0]) * dy * dy + 1)
    return U, L, Fhi + mr, Flo - mr

def cell_weights2(M, x0, x1, y0, y1, cVx, cVy):
    """as cert.cell_weights but with second-order bounds where no clamp is active in the box."""
    Px, Py = box_prob(x0, x1), box_prob(y0, y1)
    Pb = Px * Py
    P, Q, st, rmin2, rmax2 = quad_data(M, x0, x1, y0, y1)
    a, b, w0 = M[:, 0], M[:, 1], M[:, 2]
    X = np.stack([x0, x1, x1, x0], -1); Y = np.stack([y0, y0, y1, y1], -1)
    Wc = w0[None, None, :] + X[..., None] * a + Y[..., None] * b
    Dc = (Wc * Wc).sum(-1)
    Dmin = dmin_exact(M, x0, x1, y0, y1, Dc) * (1 - 1e-12)
    Dmax = Dc.max(-1) * (1 + 1e-12)
    wzmax = Wc[..., 2].max(-1)
    mx, my = moments_1d(x0, x1), moments_1d(y0, y1)
    mom = (mx, my, Px, Py, (Dmin, Dmax))
    n = len(x0)
    S = np.empty((n, 4)); I = np.empty((n, 4)); U2 = np.empty((n, 4)); L2 = np.empty((n, 4))
    reg = st == 1
    for i in range(4):
        Vx, Vy = cVx[:, i], cVy[:, i]
        S[:, i], I[:, i] = f_bounds(P, Q, rmin2, rmax2, Vx, Vy)
        # f <= 2 h_z |Ṽ| - 1 (helps near the pole, where world slopes blow up)
        Sp = 2 * np.maximum(wzmax, 0) / np.sqrt(np.maximum(Dmin, 1e-300)) * np.sqrt(1 + Vx * Vx + Vy * Vy) - 1
        S[:, i] = np.minimum(np.where(reg, S[:, i], np.inf), Sp * (1 + 1e-12) + 1e-12)
        U2[:, i], L2[:, i] = np.inf, -np.inf
        if reg.any():
            u, l, fhi, flo = second_order(M, x0[reg], x1[reg], y0[reg], y1[reg], Vx[reg], Vy[reg], Pb[reg],
                                tuple(tuple(m[reg] for m in mm) if isinstance(mm, tuple) else mm[reg] for mm in
                                      (mx, my)) + (Px[reg], Py[reg], (Dmin[reg], Dmax[reg])))
            U2[reg, i] = u - Pb[reg]; L2[reg, i] = l - Pb[reg]     # bounds of ∫ f dP
            if TAYLOR_RANGE:
                S[reg, i] = np.minimum(S[reg, i], fhi - 1); I[reg, i] = np.maximum(I[reg, i], flo - 1)
    I = np.where(reg[:, None], I, -np.inf)
    Pc = Pb[:, None]
    # c0 = ∫ max(0,f): <= P max(0,S); if I >= 0 also <= U2
    U0 = Pc * np.maximum(0, S)
    U0 = np.where(I >= 0, np.minimum(U0, U2), U0)
    # straddling f = 0: max(0,f) <= chord S (f - I)/(S - I) on [I, S]
    chord = (I < 0) & (S > 0) & np.isfinite(U2)
    with np.errstate(invalid='ignore', divide='ignore'):
        U0c = S / (S - I) * (U2 - I * Pc)
    U0 = np.where(chord, np.minimum(U0, U0c * (1 + 1e-12)), U0)
    # ℓ = ∫ (f - 1) >= max(P (I - 1), L2 - P)
    L1 = np.maximum(Pc * (I - 1), L2 - Pc)
    optA = np.broadcast_to(Pc, S.shape)
    optB = U0
    optC = U0 - L1
    sA, sB, sC = optA.sum(-1), optB.sum(-1), optC.sum(-1)
    w = np.where((sB <= sA)[:, None] & (sB <= sC)[:, None], optB, np.where((sC <= sA)[:, None], optC, optA))
    sat1 = reg & (I >= 1).all(-1); sat0 = (S <= 0).all(-1) | (st == 0)
    w = np.where(sat1[:, None], Pc, w)
    w = np.where(sat0[:, None], 0.0, w)
    # certified lower bound of ∫ clamp(f) for the refinement criterion
    band = (I >= 0) & (S <= 1)
    lb = np.where(band, np.maximum(L2, Pc * I), Pc * np.clip(I, 0, 1))
    lb = np.where((I < 0) & (S > 0) & (S <= 1) & np.isfinite(L2), np.maximum(lb, L2), lb)
    with np.errstate(invalid='ignore', divide='ignore'):
        lbc = I * Pc + (1 - I) / (S - I) * (L2 - I * Pc)
    lb = np.where((I >= 0) & (I < 1) & (S > 1) & np.isfinite(L2), np.maximum(lb, lbc), lb)
    lb = np.where(sat0[:, None], 0.0, np.where(sat1[:, None], Pc, lb))
    err = (w - lb).max(-1)
    ustar = np.minimum(np.minimum(Pc, U0), U0 - L1)      # best bound per corner alone
    ustar = np.where(sat0[:, None], 0.0, np.where(sat1[:, None], Pc, ustar))
    err_sp = np.maximum(0, (ustar - lb).max(-1))
    return w, (err, err_sp), Pb

# ======================= node placement (validity-neutral) =======================
def adaptive_axes(ls, N, c=4.5, vmax=np.tan(np.radians(89)), npre=97, refn=80, floor=0.05, kinks=()):
    """node placement (validity-neutral): equidistribute sqrt of the preview curvature along each axis."""
    sm = vmax / (c + vmax)
    s = np.linspace(-sm, sm, npre); V = c * s / (1 - np.abs(s))
    Rs = [RefE2(Lb, refn) for Lb in ls]
    VX, VY = np.meshgrid(V, V, indexing='ij')
    E = sum(R(Vview(VX.ravel(), VY.ravel())) for R in Rs).reshape(VX.shape) / len(Rs)
    roi = np.hypot(VX, VY) <= np.tan(np.radians(81))
    kx = np.zeros(npre); ky = np.zeros(npre)
    d2x = np.abs(E[2:] - 2 * E[1:-1] + E[:-2]); d2y = np.abs(E[:, 2:] - 2 * E[:, 1:-1] + E[:, :-2])
    kx[1:-1] = np.where(roi[1:-1], d2x, 0).max(1); ky[1:-1] = np.where(roi[:, 1:-1], d2y, 0).max(0)
    def nodes(k):
        dens = np.sqrt(k + floor * k.max() + 1e-12)
        cum = np.concatenate([[0], np.cumsum(0.5 * (dens[1:] + dens[:-1]))]); cum /= cum[-1]
        sn = np.interp(np.linspace(0, 1, N + 1), cum, s)
        return c * sn / (1 - np.abs(sn))
    xs = nodes(kx); ys = nodes(ky)
    if len(kinks):
        ys = np.sort(np.concatenate([ys, [k for k in kinks if abs(k) < vmax]]))
        ys = ys[np.concatenate([[True], np.diff(ys) > 1e-3])]
    return (np.unique(xs.astype(np.float32).astype(np.float64)), np.unique(ys.astype(np.float32).astype(np.float64)))
def ideal_xy(ls, xs, ys):
    Rs = [RefE2(Lb, 160) for Lb in ls]
    R = lambda wo: sum(Rr(wo) for Rr in Rs) / len(Rs)
    nx, ny = len(xs)-1, len(ys)-1
    NX, NY = np.meshgrid(xs, ys, indexing='ij')
    En = R(Vview(NX.ravel(), NY.ravel())).reshape(NX.shape)
    rng = np.random.default_rng(1); nt = 6
    i = np.repeat(np.arange(nx), ny*nt); j = np.tile(np.repeat(np.arange(ny), nt), nx)
    a_ = rng.random(len(i)); b_ = rng.random(len(i))
    Vx = xs[i] + a_*(xs[i+1]-xs[i]); Vy = ys[j] + b_*(ys[j+1]-ys[j])
    Et = R(Vview(Vx, Vy))
    pl = lambda V: (1-a_)*(1-b_)*V[i,j] + a_*(1-b_)*V[i+1,j] + (1-a_)*b_*V[i,j+1] + a_*b_*V[i+1,j+1]
    D = pl(En) - Et
    cs = np.zeros((nx, ny)); np.maximum.at(cs, (i, j), -D)
    ns = np.zeros((nx+1, ny+1))
    for di in (0,1):
        for dj in (0,1):
            ns[di:nx+di, dj:ny+dj] = np.maximum(ns[di:nx+di, dj:ny+dj], cs)
    O = pl(np.minimum(En + ns, 1)) - Et
    th = np.arctan(np.hypot(Vx, Vy))
    return 1 - O[th <= np.radians(80)].max()

# ======================= measurement harness =======================

ADAPTIVE = True

def make_lobes(a, ratio, tilt_deg, split, phi=np.radians(30), pre=np.eye(3)):
    Q = rotx(np.radians(tilt_deg))
    ls = [Lobe(a, a / ratio, phi, pre @ Q)]
    if split and tilt_deg != 0:
        ls.append(Lobe(a, a / ratio, phi, pre @ Q.T))
    return ls

def test_views(n=3000, rng=None):
    rng = rng or np.random.default_rng(7)
    th = rng.random(n) * np.radians(89.0); ph = rng.random(n) * 2 * np.pi
    return th, view(th, ph)

def run(a, ratio, tilt, split, N=32, c=3.0, vmax=np.tan(np.radians(89)), eta=1e-4, refn=300,
        nviews=3000, kinks=True, verbose=True, phi=np.radians(30), align=True, tau=None):
    one_d = (ratio == 1 and tilt == 0)
    gamma = phi if (tilt == 0 and align) else 0.0
    pre = rotz(-gamma)
    ls = make_lobes(a, ratio, tilt, split, phi, pre)          # certified (grid-aligned) lobes
    ls0 = make_lobes(a, ratio, tilt, split, phi)              # reference lobes (world frame)
    t0 = time.time(); st = dict(evals=0, leaves=0, cells=0)
    vs = []
    if one_d:
        rs = axis_nodes(2 * N, vmax, c); rs = rs[rs >= 0]
        if rs[0] != 0: rs = np.concatenate([[0.0], rs])
        xs, ys = rs, np.array([0.0, 0.0])
    else:
        if ADAPTIVE:
            xs, ys = adaptive_axes(ls, N, c=c, vmax=vmax, npre=65, refn=40, floor=0.02,
                                   kinks=tilt_kinks(ls) if (kinks and tilt) else [])
        else:
            xs = axis_nodes(N, vmax, c); ys = axis_nodes(N, vmax, c, tilt_kinks(ls) if kinks else [])
    for Lb in ls:
        v, s = certify(Lb, xs, ys, eta) if tau is None else certify_budget(Lb, xs, ys, tau)
        vs.append(v)
        for k in ('evals', 'leaves', 'cells'): st[k] += s[k]
    v = sum(vs) / len(vs); v = v + 1e-15 * np.abs(v) + 1e-15
    tcert = time.time() - t0
    if one_d:
        tab = Table1D(xs, v[:, 0]); eb = ebar_lower_1d(tab)
    else:
        tab = Table(xs, ys, v); eb = ebar_lower2(tab)
    th, wo = test_views(nviews)
    if not one_d:   # plus the cell-centre views
        Xc, Yc = np.meshgrid(0.5 * (xs[1:] + xs[:-1]), 0.5 * (ys[1:] + ys[:-1]), indexing='ij')
        Wc = np.stack([Xc.ravel(), Yc.ravel(), np.ones(Xc.size)], -1)
        Wc /= np.linalg.norm(Wc, axis=-1, keepdims=True)
        Wc = Wc @ pre                       # back to world frame (pre^-1 = pre^T)
        thc = np.arccos(Wc[:, 2]); sel = thc <= np.radians(89)
        th = np.concatenate([th, thc[sel]]); wo = np.concatenate([wo, Wc[sel]])
    refs = [RefE2(Lb, refn) for Lb in ls0]
    E = sum(R(wo) for R in refs) / len(refs)
    Eh = tab(wo @ pre.T).astype(np.float64)
    eba = ebar_accurate(lambda w: tab(w))   # table frame is rotation of world; cos-weighted mean invariant
    fur = E + 1 - Eh
    furK = E + (1 - Eh) * (1 - eba) / (1 - eb)     # with the Ē actually used
    m80 = th <= np.radians(80)
    res = dict(a=a, ratio=ratio, tilt=tilt, split=split, N=N, eta=eta, nx=len(xs), ny=len(ys), one_d=one_d,
               f80=fur[m80].min(), f89=fur.min(), fmed80=np.median(fur[m80]), fK80=furK[m80].min(),
               dmin=(Eh - E).min(), ebar=eb, ebar_acc=eba, tcert=tcert, evals=st['evals'], leaves=st['leaves'],
               cells=st['cells'], lpc=st['leaves'] / max(st['cells'], 1))
    if verbose:
        print("a=%-6g 1:%-2d tilt=%-2d split=%d N=%d(%dx%d) eta=%.0e | furn80 %.4f furn89 %.4f med80 %.4f (withEbar %.4f) | "
              "min(Eh-E) %.2e | Ebar %.4f (acc %.4f) | evals %.2e leaves/cell %.0f | %.1fs" % (
              a, ratio, tilt, split, N, len(xs), len(ys), eta, res['f80'], res['f89'], res['fmed80'], res['fK80'],
              res['dmin'], eb, eba, st['evals'], res['lpc'], tcert), flush=True)
    return res


if __name__ == '__main__':
    a, r, t, s = float(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    N = int(sys.argv[5]) if len(sys.argv) > 5 else 32
    eta = float(sys.argv[6]) if len(sys.argv) > 6 else 1e-4
    c = float(sys.argv[7]) if len(sys.argv) > 7 else (3.0 if (r == 1 and t == 0) else 4.5)
    run(a, r, t, s, N=N, eta=eta, c=c, nviews=2000)
