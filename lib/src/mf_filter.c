/* mf_filter.c -- NDF filtering over a pixel footprint in slope space (see mf_filter.h and
 * docs/math.md, "NDF filtering and slope moments"). */
#include "mfkit/mf_filter.h"

#include <float.h>

/* ---- footprint to slope space ------------------------------------------------------------- */

void mf_filter_half_slope(mf_vec3 wo, mf_vec3 wi, double h[2])
{
    mf_vec3 s = mf_vec3_add(wo, wi);
    if (!mf_vec3_isfinite(s) || !(s.z > 0.0)) {
        h[0] = h[1] = NAN;
        return;
    }
    /* [Kaplanyan 2016, Eq. 3] h_w = (i + o) / (n . (i + o)), T = identity; mfkit sign (C-L6) */
    h[0] = -s.x / s.z;
    h[1] = -s.y / s.z;
}

void mf_filter_half_slope_jacobian_planar(mf_vec3 eye, mf_vec3 light, mf_vec3 x, double jac[2][2])
{
    mf_vec3 to_e = mf_vec3_sub(eye, x), to_l = mf_vec3_sub(light, x);
    double d_o = mf_vec3_length(to_e), d_i = mf_vec3_length(to_l);
    if (!mf_vec3_isfinite(eye) || !mf_vec3_isfinite(light) || !mf_vec3_isfinite(x) || !(to_e.z > 0.0)
        || !(to_l.z > 0.0) || !(d_o > 0.0) || !(d_i > 0.0)) {
        jac[0][0] = jac[0][1] = jac[1][0] = jac[1][1] = NAN;
        return;
    }
    mf_vec3 o = mf_vec3_scale(to_e, 1.0 / d_o), in = mf_vec3_scale(to_l, 1.0 / d_i);
    double H[3] = {o.x + in.x, o.y + in.y, o.z + in.z};
    double ov[3] = {o.x, o.y, o.z}, iv[3] = {in.x, in.y, in.z};
    /* d o / d x_j = -(e_j - o o_j) / |eye - x| (moving x by e_j moves the eye direction the other
     * way, projected orthogonally to o); likewise for the light direction. */
    for (int j = 0; j < 2; ++j) {
        double dH[3];
        for (int k = 0; k < 3; ++k) {
            double delta = (k == j) ? 1.0 : 0.0;
            dH[k] = -(delta - ov[k] * ov[j]) / d_o - (delta - iv[k] * iv[j]) / d_i;
        }
        /* h_k = -H_k / H_z  =>  dh_k = -(dH_k H_z - H_k dH_z) / H_z^2 */
        for (int k = 0; k < 2; ++k)
            jac[k][j] = -(dH[k] * H[2] - H[k] * dH[2]) / (H[2] * H[2]);
    }
}

void mf_filter_footprint_to_slope(const double jac[2][2], const double dx_u[2], const double dx_v[2],
                                  double dh_u[2], double dh_v[2])
{
    /* [Kaplanyan 2016, Eq. 5] as dh = M dx with M of Eq. 4 (column vectors) */
    double u0 = jac[0][0] * dx_u[0] + jac[0][1] * dx_u[1];
    double u1 = jac[1][0] * dx_u[0] + jac[1][1] * dx_u[1];
    double v0 = jac[0][0] * dx_v[0] + jac[0][1] * dx_v[1];
    double v1 = jac[1][0] * dx_v[0] + jac[1][1] * dx_v[1];
    dh_u[0] = u0;
    dh_u[1] = u1;
    dh_v[0] = v0;
    dh_v[1] = v1;
}

mf_sym2 mf_filter_footprint_covariance(const double dh_u[2], const double dh_v[2], double s)
{
    if (!isfinite(dh_u[0]) || !isfinite(dh_u[1]) || !isfinite(dh_v[0]) || !isfinite(dh_v[1]) || !(s >= 0.0)
        || !isfinite(s)) {
        mf_sym2 bad = {NAN, NAN, NAN};
        return bad;
    }
    /* [Kaplanyan 2016, Eq. 13] corrected (docs/math.md, correction C-K4): J^T J = sum of outer products */
    double s_sq = s * s;
    mf_sym2 p = {s_sq * (dh_u[0] * dh_u[0] + dh_v[0] * dh_v[0]), s_sq * (dh_u[0] * dh_u[1] + dh_v[0] * dh_v[1]),
                 s_sq * (dh_u[1] * dh_u[1] + dh_v[1] * dh_v[1])};
    return p;
}

void mf_filter_footprint_rect(const double dh_u[2], const double dh_v[2], double width[2])
{
    /* [Kaplanyan 2016, Sec. 4.3]: the corners are h +- dh_u/2 +- dh_v/2 */
    width[0] = fabs(dh_u[0]) + fabs(dh_v[0]);
    width[1] = fabs(dh_u[1]) + fabs(dh_v[1]);
    if (!isfinite(width[0]) || !isfinite(width[1]))
        width[0] = width[1] = NAN;
}

double mf_filter_clamp_parallelogram(double dh_u[2], double dh_v[2], double lambda)
{
    double extent = fmax(hypot(dh_u[0] + dh_v[0], dh_u[1] + dh_v[1]), hypot(dh_u[0] - dh_v[0], dh_u[1] - dh_v[1]));
    if (!(lambda > 0.0) || !isfinite(extent)) {
        dh_u[0] = dh_u[1] = dh_v[0] = dh_v[1] = NAN;
        return NAN;
    }
    if (extent <= lambda) /* [Kaplanyan 2016, Sec. 5.2] */
        return 1.0;
    double scale = lambda / extent;
    dh_u[0] *= scale;
    dh_u[1] *= scale;
    dh_v[0] *= scale;
    dh_v[1] *= scale;
    return scale;
}

void mf_filter_clamp_rect(double width[2], double lambda, double epsilon)
{
    if (!(epsilon >= 0.0) || !(lambda >= epsilon) || !(lambda > 0.0) || !(width[0] >= 0.0) || !(width[1] >= 0.0)
        || !isfinite(width[0]) || !isfinite(width[1])) {
        width[0] = width[1] = NAN;
        return;
    }
    for (int k = 0; k < 2; ++k) /* [Kaplanyan 2016, Sec. 5.2] */
        width[k] = fmin(fmax(width[k], epsilon), lambda);
}

/* ---- Beckmann ----------------------------------------------------------------------------- */

static int sym2_psd(mf_sym2 p)
{
    return isfinite(p.xx) && isfinite(p.xy) && isfinite(p.yy) && p.xx >= 0.0 && p.yy >= 0.0
        && p.xx * p.yy - p.xy * p.xy >= -16.0 * DBL_EPSILON * p.xx * p.yy;
}

/* Sum of a valid covariance and a positive semi-definite p; a determinant that is negative by
 * rounding only (p of rank one, zero base) is clamped to 0. */
static mf_gaussian_slopes gaussian_plus(double mean_x, double mean_y, double vx, double vy, double cxy, mf_sym2 p)
{
    mf_gaussian_slopes g = {mean_x, mean_y, vx + p.xx, vy + p.yy, cxy + p.xy};
    double cmax = sqrt(g.var_x * g.var_y);
    if (fabs(g.cov_xy) > cmax)
        g.cov_xy = copysign(cmax, g.cov_xy);
    return g;
}

mf_gaussian_slopes mf_filter_beckmann(double alpha_x, double alpha_y, mf_sym2 p)
{
    if (!(alpha_x >= 0.0) || !(alpha_y >= 0.0) || !isfinite(alpha_x) || !isfinite(alpha_y) || !sym2_psd(p)) {
        mf_gaussian_slopes bad = {NAN, NAN, NAN, NAN, NAN};
        return bad;
    }
    /* [Kaplanyan 2016, Eq. 14-15]: B' = diag(alpha^2 / 2) + P */
    return gaussian_plus(0.0, 0.0, 0.5 * alpha_x * alpha_x, 0.5 * alpha_y * alpha_y, 0.0, p);
}

mf_gaussian_slopes mf_filter_gaussian_add(const mf_gaussian_slopes *g, mf_sym2 p)
{
    if (!mf_gaussian_valid(g) || !sym2_psd(p)) {
        mf_gaussian_slopes bad = {NAN, NAN, NAN, NAN, NAN};
        return bad;
    }
    /* [Kaplanyan 2016, Eq. 21]: nested convolution = sum of covariances */
    return gaussian_plus(g->mean_x, g->mean_y, g->var_x, g->var_y, g->cov_xy, p);
}

/* ---- GGX over a slope rectangle ----------------------------------------------------------- */

/* In the stretched coordinates u = s / alpha_x, v = t / alpha_y the GGX slope density is
 * p(u, v) = (1 + u^2 + v^2)^-2 / pi per unit (u, v) area; everything below works there. */

/* Largest stretched coordinate accepted (squares and products stay finite). */
#define RECT_MAX_COORD 1e100
/* Stretched widths below this are replaced by their midpoint: the mean over [a - w/2, a + w/2] of
 * q(a) = (c^2 + a^2)^-2 differs from q(a) by at most w^2 max|q''/q| / 24 <= w^2 (c >= 1). */
#define RECT_TINY_WIDTH 1e-9
/* Condition number of the edge sum above which the semi-analytic form is used. */
#define RECT_MAX_COND 16.0

double mf_filter_ggx_rect_antiderivative(double alpha_x, double alpha_y, double s, double t)
{
    if (!(alpha_x > 0.0) || !(alpha_y > 0.0) || !isfinite(alpha_x) || !isfinite(alpha_y) || !isfinite(s)
        || !isfinite(t))
        return NAN;
    /* [Kaplanyan 2016, Appendix A]: phi(s, t, ax, ay) = u atan(v / sqrt(1 + u^2)) / sqrt(1 + u^2) */
    double u = s / alpha_x, v = t / alpha_y;
    double qu = hypot(1.0, u), qv = hypot(1.0, v); /* no overflow for huge u, v */
    return (u / qu * atan(v / qu) + v / qv * atan(u / qv)) / (2.0 * MF_PI);
}

/* x - sin(x) for x >= 0 without cancellation: Taylor series below 1 (terms to x^19/19!, the
 * next is < 1e-19 relative), direct above (x - sin x >= 0.158 x there). */
static double x_minus_sin(double x)
{
    if (x >= 1.0)
        return x - sin(x);
    double x2 = x * x;
    double r = 1.0 / 121645100408832000.0;           /* 1/19! */
    r = 1.0 / 355687428096000.0 - x2 * r;           /* 1/17! */
    r = 1.0 / 1307674368000.0 - x2 * r;             /* 1/15! */
    r = 1.0 / 6227020800.0 - x2 * r;                /* 1/13! */
    r = 1.0 / 39916800.0 - x2 * r;                  /* 1/11! */
    r = 1.0 / 362880.0 - x2 * r;                    /* 1/9!  */
    r = 1.0 / 5040.0 - x2 * r;                      /* 1/7!  */
    r = 1.0 / 120.0 - x2 * r;                       /* 1/5!  */
    r = 1.0 / 6.0 - x2 * r;                         /* 1/3!  */
    return x * x2 * r;
}

/* integral_{a0}^{a1} (c^2 + a^2)^-2 da for c >= 1, a1 - a0 = w >= 0 (w passed separately so
 * that an exact width is not recomputed from rounded ends), as a sum of non-negative terms.
 * With a = c tan(psi), da / (c^2 + a^2)^2 = cos^2(psi) dpsi / c^3, so the integral is
 *   (dpsi + sin(dpsi) cos(psi0 + psi1)) / (2 c^3)
 *   = ((dpsi - sin dpsi) + 2 cos^2(psi_mean) sin dpsi) / (2 c^3),
 * dpsi = psi1 - psi0 = atan2(w c, c^2 + a0 a1) from the exact width, and cos(psi_mean) =
 * sin(chi_mean) with chi = pi/2 - psi = atan2(c, a) (accurate also where psi -> pi/2).  The
 * integrand is even in a: the interval is reflected so that a0 + a1 >= 0 (chi_mean <= pi/2). */
static double strip_integral(double a0, double a1, double w, double c, double c_sq)
{
    if (a0 + a1 < 0.0) {
        double t = a0;
        a0 = -a1;
        a1 = -t;
    }
    double dpsi = atan2(w * c, c_sq + a0 * a1);
    double chi_mean = 0.5 * (atan2(c, a0) + atan2(c, a1));
    double sc = sin(chi_mean);
    return (x_minus_sin(dpsi) + 2.0 * sc * sc * sin(dpsi)) / (2.0 * c * c_sq);
}

/* One edge term of the edge form of 2 pi (F(u1,v1) - F(u0,v1) - F(u1,v0) + F(u0,v0)):
 *   E(x; y0, y1) = x / sqrt(1 + x^2) (atan(y1 / sqrt(1 + x^2)) - atan(y0 / sqrt(1 + x^2)))
 * with the atan difference as one atan2 of the exact width w = y1 - y0:
 *   atan(y1/q) - atan(y0/q) = atan2(w q, q^2 + y0 y1),  q = sqrt(1 + x^2),
 * whose arguments are |p0 x p1| and p0 . p1 of p = (x, y, 1): relative error ~eps. */
static double edge_term(double x, double y0, double y1, double w)
{
    double q_sq = 1.0 + x * x, q = sqrt(q_sq);
    return x / q * atan2(w * q, q_sq + y0 * y1);
}

/* 16-point Gauss-Legendre on [-1, 1]: positive nodes and their weights (40-digit computation,
 * rounded). */
static const double gl16_x[8] = {
    0.0950125098376374401853, 0.281603550779258913230, 0.458016777657227386342, 0.617876244402643748447,
    0.755404408355003033895,  0.865631202387831743880, 0.944575023073232576078, 0.989400934991649932596};
static const double gl16_w[8] = {
    0.189450610455068496285,  0.182603415044923588867,  0.169156519395002538189,  0.149595988816576732082,
    0.124628971255533872052,  0.0951585116824927848099, 0.0622535239386478928628, 0.0271524594117540948518};

/* An axis-aligned interval of stretched coordinates: ends a0 <= a1 and width w = a1 - a0 (each
 * exact where the caller had it exact). */
typedef struct rect_side {
    double a0, a1, w;
} rect_side;

/* Distance from 0 to the interval. */
static double side_dist0(rect_side s) { return (s.a0 <= 0.0 && s.a1 >= 0.0) ? 0.0 : fmin(fabs(s.a0), fabs(s.a1)); }

/* integral over t in [t0, t0 + len] of the strip integral over side u at v = vb + sign t. */
static double panel_gl16(rect_side u, double vb, double sign, double t0, double len)
{
    double half = 0.5 * len, mid = t0 + half, sum = 0.0;
    for (int i = 0; i < 8; ++i) {
        for (int k = -1; k <= 1; k += 2) {
            double v = vb + sign * (mid + k * half * gl16_x[i]);
            double c_sq = 1.0 + v * v;
            sum += gl16_w[i] * strip_integral(u.a0, u.a1, u.w, sqrt(c_sq), c_sq);
        }
    }
    return half * sum;
}

/* integral over t in [0, len] of the strip integral at v = vb + sign t, where |v| grows with t
 * (vb is the point nearest to v = 0).  The integrand's singularities are at v = +-i sqrt(1 + u^2),
 * u in the strip, at distance >= max(|v|, d0) from a real v (d0 = sqrt(1 + u_min^2)).  Panels of
 * length max(|v_start|, d0) keep them >= 2 half-widths away from every panel, where the 16-point
 * rule converges like 4.6^-32 (Bernstein ellipse); the panel lengths grow geometrically, so a
 * side of stretched length L needs about log2(L / d0) + 2 panels of 16 points (~25 panels for the
 * tested range L <= 1e7, ~335 at the domain limit 1e100). */
static double graded_integral(rect_side u, double d0, double vb, double sign, double len)
{
    double t = 0.0, sum = 0.0;
    while (t < len) {
        double step = fmax(fabs(vb) + t, d0);
        if (len - t <= step) { /* last panel ends exactly at len */
            sum += panel_gl16(u, vb, sign, t, len - t);
            break;
        }
        sum += panel_gl16(u, vb, sign, t, step);
        t += step;
    }
    return sum;
}

/* integral over the rectangle u x v of (1 + u^2 + v^2)^-2, closed form along u and
 * Gauss-Legendre along v.  The panel weights come from the exact width of v, so tiny rectangles
 * far from the peak keep their exact area. */
static double semi_analytic(rect_side u, rect_side v)
{
    double d = side_dist0(u), d0 = sqrt(1.0 + d * d);
    if (v.a0 >= 0.0) /* one piece, growing away from v = 0 */
        return graded_integral(u, d0, v.a0, 1.0, v.w);
    if (v.a1 <= 0.0) /* the same, mirrored (the integrand is even in v) */
        return graded_integral(u, d0, v.a1, -1.0, v.w);
    /* the strip straddles v = 0: two pieces growing away from it */
    return graded_integral(u, d0, 0.0, -1.0, -v.a0) + graded_integral(u, d0, 0.0, 1.0, v.a1);
}

/* Mean of p(u, v) = (1 + u^2 + v^2)^-2 / pi over the rectangle u x v. */
static double unit_rect_mean(rect_side u, rect_side v)
{
    int tiny_u = u.w < RECT_TINY_WIDTH, tiny_v = v.w < RECT_TINY_WIDTH;
    double um = 0.5 * u.a0 + 0.5 * u.a1, vm = 0.5 * v.a0 + 0.5 * v.a1;
    if (tiny_u && tiny_v) {
        double s = 1.0 + um * um + vm * vm;
        return 1.0 / (MF_PI * s * s);
    }
    if (tiny_u) {
        double c_sq = 1.0 + um * um;
        return strip_integral(v.a0, v.a1, v.w, sqrt(c_sq), c_sq) / (MF_PI * v.w);
    }
    if (tiny_v) {
        double c_sq = 1.0 + vm * vm;
        return strip_integral(u.a0, u.a1, u.w, sqrt(c_sq), c_sq) / (MF_PI * u.w);
    }
    /* Closed form [Kaplanyan 2016, Appendix A, correction C-K1], regrouped by edges (docs/math.md). */
    double e1 = edge_term(u.a1, v.a0, v.a1, v.w), e2 = edge_term(u.a0, v.a0, v.a1, v.w);
    double e3 = edge_term(v.a1, u.a0, u.a1, u.w), e4 = edge_term(v.a0, u.a0, u.a1, u.w);
    double sum = (e1 - e2) + (e3 - e4);
    double mag = fabs(e1) + fabs(e2) + fabs(e3) + fabs(e4);
    if (sum > 0.0 && mag <= RECT_MAX_COND * sum)
        return sum / (2.0 * MF_PI * u.w * v.w);
    /* Cancellation: integrate numerically along the axis that needs fewer panels. */
    double du = side_dist0(u), dv = side_dist0(v);
    double integral = (v.w / sqrt(1.0 + du * du) <= u.w / sqrt(1.0 + dv * dv)) ? semi_analytic(u, v)
                                                                               : semi_analytic(v, u);
    return integral / (MF_PI * u.w * v.w);
}

static int rect_args_valid(double alpha_x, double alpha_y)
{
    return alpha_x > 0.0 && alpha_y > 0.0 && isfinite(alpha_x) && isfinite(alpha_y);
}

/* P22(s, t) ds dt = p(u, v) du dv, so the mean over the rectangle is unit_rect_mean / (alpha_x
 * alpha_y); stretched sides beyond RECT_MAX_COORD go to rect_mean_large. */
static int side_within(rect_side s, double lim) { return fabs(s.a0) <= lim && fabs(s.a1) <= lim && s.w <= lim; }

/* m / (alpha_x alpha_y) * 2^scale2 with one rounding at the end: no intermediate overflow or
 * underflow (the exponents are added as integers). */
static double scaled_quotient(double m, double alpha_x, double alpha_y, int scale2)
{
    int em, ex, ey;
    double fm = frexp(m, &em), fx = frexp(alpha_x, &ex), fy = frexp(alpha_y, &ey);
    return ldexp(fm / fx / fy, em - ex - ey + scale2);
}

/* The edge term with every product scaled by 1/M^2, M = max(q, |y0|, |y1|): the same angle
 * (atan2 is invariant to a common positive factor) without overflow for coordinates up to
 * DBL_MAX; q = hypot(1, x). */
static double edge_term_scaled(double x, double y0, double y1, double w)
{
    double q = hypot(1.0, x);
    double m = fmax(q, fmax(fabs(y0), fabs(y1)));
    double qs = q / m, ws = w / m;
    return x / q * atan2(ws * qs, qs * qs + (y0 / m) * (y1 / m));
}

/* The mean for stretched coordinates beyond RECT_MAX_COORD (finite):
 *  - far from the peak (distance d > RECT_MAX_COORD): 1 + u^2 + v^2 = u^2 + v^2 to 1e-200, which
 *    is homogeneous of degree -4, so the mean over R is 2^(-4k) times the mean over R / 2^k; k
 *    brings the nearest point to ~2^50 (1 is still negligible there: 1e-30);
 *  - otherwise the edge form, with the atan2 arguments scaled (edge_term_scaled) and the division
 *    by the area done in exponent arithmetic; where its edges cancel (condition above
 *    RECT_MAX_COND) and the far-field scaling does not apply, no accurate value is available:
 *    NaN (mf_filter.h states the domain). */
static double rect_mean_large(double alpha_x, double alpha_y, rect_side u, rect_side v)
{
    double du = side_dist0(u), dv = side_dist0(v), d = hypot(du, dv);
    if (d > RECT_MAX_COORD) {
        int e;
        (void)frexp(d, &e);
        int k = e - 50;
        rect_side us = {ldexp(u.a0, -k), ldexp(u.a1, -k), ldexp(u.w, -k)};
        rect_side vs = {ldexp(v.a0, -k), ldexp(v.a1, -k), ldexp(v.w, -k)};
        if (side_within(us, RECT_MAX_COORD) && side_within(vs, RECT_MAX_COORD))
            return scaled_quotient(unit_rect_mean(us, vs), alpha_x, alpha_y, -4 * k);
        return NAN;
    }
    double e1 = edge_term_scaled(u.a1, v.a0, v.a1, v.w), e2 = edge_term_scaled(u.a0, v.a0, v.a1, v.w);
    double e3 = edge_term_scaled(v.a1, u.a0, u.a1, u.w), e4 = edge_term_scaled(v.a0, u.a0, u.a1, u.w);
    double sum = (e1 - e2) + (e3 - e4);
    double mag = fabs(e1) + fabs(e2) + fabs(e3) + fabs(e4);
    if (!(sum > 0.0 && mag <= RECT_MAX_COND * sum))
        return NAN;
    /* sum / (2 pi u.w v.w alpha_x alpha_y), u.w v.w may overflow */
    int eu, ev;
    double fu = frexp(u.w, &eu), fv = frexp(v.w, &ev);
    return scaled_quotient(sum / (2.0 * MF_PI) / fu / fv, alpha_x, alpha_y, -eu - ev);
}

static double rect_mean_stretched(double alpha_x, double alpha_y, rect_side u, rect_side v)
{
    if (!isfinite(u.a0) || !isfinite(u.a1) || !isfinite(u.w) || !isfinite(v.a0) || !isfinite(v.a1)
        || !isfinite(v.w))
        return NAN;
    if (!side_within(u, RECT_MAX_COORD) || !side_within(v, RECT_MAX_COORD))
        return rect_mean_large(alpha_x, alpha_y, u, v);
    return unit_rect_mean(u, v) / alpha_x / alpha_y;
}

double mf_filter_ggx_rect_mean(double alpha_x, double alpha_y, double cx, double cy, double wx, double wy)
{
    if (!rect_args_valid(alpha_x, alpha_y) || !isfinite(cx) || !isfinite(cy) || !(wx >= 0.0) || !(wy >= 0.0)
        || !isfinite(wx) || !isfinite(wy))
        return NAN;
    rect_side u = {(cx - 0.5 * wx) / alpha_x, (cx + 0.5 * wx) / alpha_x, wx / alpha_x};
    rect_side v = {(cy - 0.5 * wy) / alpha_y, (cy + 0.5 * wy) / alpha_y, wy / alpha_y};
    return rect_mean_stretched(alpha_x, alpha_y, u, v);
}

double mf_filter_ggx_rect_mean_bounds(double alpha_x, double alpha_y, double x0, double x1, double y0, double y1)
{
    if (!rect_args_valid(alpha_x, alpha_y) || !isfinite(x0) || !isfinite(x1) || !isfinite(y0) || !isfinite(y1)
        || !(x1 >= x0) || !(y1 >= y0))
        return NAN;
    rect_side u = {x0 / alpha_x, x1 / alpha_x, (x1 - x0) / alpha_x};
    rect_side v = {y0 / alpha_y, y1 / alpha_y, (y1 - y0) / alpha_y};
    return rect_mean_stretched(alpha_x, alpha_y, u, v);
}

/* ---- GGX proxy roughness ------------------------------------------------------------------ */

double mf_filter_ggx_proxy_alpha(double alpha, double dh)
{
    if (!(alpha > 0.0) || !isfinite(alpha) || !(dh >= 0.0) || !isfinite(dh))
        return NAN;
    if (dh == 0.0)
        return alpha;
    /* [Kaplanyan 2016, Eq. 19] solved exactly (correction C-K3):
     *   alpha'^2 = dh q / (4 atan(dh / q)),  q = sqrt(4 alpha^2 + dh^2).
     * Rearranged with dh q = (dh^2 / t) ... = 4 (alpha^2 + dh^2/4) t: no 0/0 as dh -> 0. */
    /* Scaled by the power of two e of the larger input, so that the squares neither overflow
     * (dh >= 1e155) nor lose a subnormal dh: scaling by 2^-e is exact, so inputs that needed no
     * scaling give the same bits as without it. */
    int e;
    (void)frexp(fmax(alpha, dh), &e);
    double a = ldexp(alpha, -e), d = ldexp(dh, -e);
    double q = hypot(2.0 * a, d), t = d / q;
    /* t / atan(t) = 1 + t^2/3 - ...: exactly 1 in double below 2^-27 (t^2/3 < 2^-55), where
     * t / atan(t) would be 0/0 once t underflows (a subnormal dh against alpha >= 1). */
    double ratio = t < 0x1p-27 ? 1.0 : t / atan(t);
    double a_sq = (a * a + 0.25 * d * d) * ratio;
    return ldexp(sqrt(a_sq), e);
}

double mf_filter_ggx_proxy_alpha_approx(double alpha, double dh)
{
    if (!(alpha > 0.0) || !isfinite(alpha) || !(dh >= 0.0) || !isfinite(dh))
        return NAN;
    return hypot(alpha, dh); /* [Kaplanyan 2016, Eq. 20, right] */
}

void mf_filter_ggx_proxy_alpha_per_axis(double alpha_x, double alpha_y, double wx, double wy, double out[2])
{
    out[0] = mf_filter_ggx_proxy_alpha(alpha_x, wx);
    out[1] = mf_filter_ggx_proxy_alpha(alpha_y, wy);
    if (isnan(out[0]) || isnan(out[1]))
        out[0] = out[1] = NAN;
}

mf_status mf_filter_ggx_proxy_alpha_joint(double alpha_x, double alpha_y, double wx, double wy, double out[2])
{
    out[0] = out[1] = NAN;
    double c = mf_filter_ggx_rect_mean(alpha_x, alpha_y, 0.0, 0.0, wx, wy);
    if (!(c > 0.0) || !isfinite(c))
        return MF_ERR_DOMAIN;
    /* (19) alpha'_x alpha'_y = 1 / (pi C);  (M) alpha'_x / alpha'_y = rho */
    double rho = hypot(2.0 * alpha_x, wx) / hypot(2.0 * alpha_y, wy);
    double prod = 1.0 / (MF_PI * c);
    out[0] = sqrt(prod * rho);
    out[1] = sqrt(prod / rho);
    return MF_OK;
}
