/* mf_moments.c -- LEAN/LEADR slope moments, Hery bump roughness, Toksvig (see mf_moments.h). */
#include "mfkit/mf_moments.h"

#include <float.h>

static mf_slope_moments moments_nan(void)
{
    mf_slope_moments m = {NAN, NAN, NAN, NAN, NAN};
    return m;
}

static int moments_finite(const mf_slope_moments *m)
{
    return m && isfinite(m->mean_x) && isfinite(m->mean_y) && isfinite(m->m_xx) && isfinite(m->m_xy)
        && isfinite(m->m_yy);
}

static int sym2_finite(mf_sym2 a) { return isfinite(a.xx) && isfinite(a.xy) && isfinite(a.yy); }

mf_slope_moments mf_moments_from_slope(double sx, double sy)
{
    if (!isfinite(sx) || !isfinite(sy))
        return moments_nan();
    /* [Olano 2010, Eq. 3-4] in the mfkit sign (docs/math.md, correction C-N4). */
    mf_slope_moments m = {sx, sy, sx * sx, sx * sy, sy * sy};
    return m;
}

mf_slope_moments mf_moments_from_normal(mf_vec3 n)
{
    if (!mf_vec3_isfinite(n) || !(n.z > 0.0))
        return moments_nan();
    /* height gradient (-n.x/n.z, -n.y/n.z) [Dupuy 2013, Sec. 4.1]; LEAN's B = +n.xy/n.z */
    return mf_moments_from_slope(-n.x / n.z, -n.y / n.z);
}

mf_slope_moments mf_moments_from_lean(double bx, double by, double mxx, double mxy, double myy)
{
    mf_slope_moments m = {-bx, -by, mxx, mxy, myy}; /* correction C-N4: LEADR mean = -B */
    if (!moments_finite(&m))
        return moments_nan();
    return m;
}

void mf_moments_accumulate(mf_slope_moments *acc, const mf_slope_moments *m, double w)
{
    acc->mean_x += w * m->mean_x;
    acc->mean_y += w * m->mean_y;
    acc->m_xx += w * m->m_xx;
    acc->m_xy += w * m->m_xy;
    acc->m_yy += w * m->m_yy;
}

mf_gaussian_slopes mf_moments_to_gaussian(const mf_slope_moments *m)
{
    mf_gaussian_slopes bad = {NAN, NAN, NAN, NAN, NAN};
    if (!moments_finite(m))
        return bad;
    /* [Olano 2010, Eq. 5; Dupuy 2013, Eq. 9]: Sigma = M - E E^T */
    double ex = m->mean_x, ey = m->mean_y;
    double vx = m->m_xx - ex * ex, vy = m->m_yy - ey * ey, c = m->m_xy - ex * ey;
    /* Rounding slack of the subtractions: a few ulps of the operands. */
    double tol_x = 16.0 * DBL_EPSILON * (fabs(m->m_xx) + ex * ex);
    double tol_y = 16.0 * DBL_EPSILON * (fabs(m->m_yy) + ey * ey);
    if (vx < -tol_x || vy < -tol_y)
        return bad;
    if (vx < 0.0)
        vx = 0.0;
    if (vy < 0.0)
        vy = 0.0;
    /* |cov| <= sqrt(vx vy) (Cauchy-Schwarz), up to the rounding of the three subtractions */
    double cmax = sqrt(vx * vy);
    if (fabs(c) > cmax) { /* allowed if within the rounding of the variances and of c itself */
        double c_lim = sqrt((vx + tol_x) * (vy + tol_y)) + 16.0 * DBL_EPSILON * (fabs(m->m_xy) + fabs(ex * ey));
        if (fabs(c) > c_lim)
            return bad;
        c = copysign(cmax, c);
    }
    mf_gaussian_slopes g = {ex, ey, vx, vy, c};
    return g;
}

mf_slope_moments mf_moments_add_covariance(const mf_slope_moments *m, mf_sym2 c)
{
    if (!moments_finite(m) || !sym2_finite(c))
        return moments_nan();
    /* [Olano 2010, Eq. 6] generalised: adding c to M adds c to Sigma = M - E E^T. */
    mf_slope_moments r = *m;
    r.m_xx += c.xx;
    r.m_xy += c.xy;
    r.m_yy += c.yy;
    return r;
}

mf_slope_moments mf_moments_add_beckmann(const mf_slope_moments *m, double alpha_x, double alpha_y)
{
    if (!(alpha_x >= 0.0) || !(alpha_y >= 0.0) || !isfinite(alpha_x) || !isfinite(alpha_y))
        return moments_nan();
    mf_sym2 c = {0.5 * alpha_x * alpha_x, 0.0, 0.5 * alpha_y * alpha_y}; /* sigma^2 = alpha^2 / 2 */
    return mf_moments_add_covariance(m, c);
}

mf_slope_moments mf_moments_scale(const mf_slope_moments *m, double eta)
{
    if (!moments_finite(m) || !isfinite(eta))
        return moments_nan();
    /* [Dupuy 2013, Sec. 4.2, Height Scaling] */
    double eta_sq = eta * eta;
    mf_slope_moments r = {eta * m->mean_x, eta * m->mean_y, eta_sq * m->m_xx, eta_sq * m->m_xy, eta_sq * m->m_yy};
    return r;
}

mf_slope_moments mf_moments_transform(const mf_slope_moments *m, double du_dx, double dv_dx, double du_dy,
                                      double dv_dy)
{
    if (!moments_finite(m) || !isfinite(du_dx) || !isfinite(dv_dx) || !isfinite(du_dy) || !isfinite(dv_dy))
        return moments_nan();
    /* [Dupuy 2013, Eq. 12]: (x, y) slopes = A (u, v) slopes with A rows (du_dx, dv_dx), (du_dy, dv_dy). */
    mf_slope_moments r;
    r.mean_x = du_dx * m->mean_x + dv_dx * m->mean_y;
    r.mean_y = du_dy * m->mean_x + dv_dy * m->mean_y;
    r.m_xx = du_dx * du_dx * m->m_xx + dv_dx * dv_dx * m->m_yy + 2.0 * du_dx * dv_dx * m->m_xy;
    r.m_yy = du_dy * du_dy * m->m_xx + dv_dy * dv_dy * m->m_yy + 2.0 * du_dy * dv_dy * m->m_xy;
    r.m_xy = du_dx * du_dy * m->m_xx + dv_dx * dv_dy * m->m_yy + (du_dx * dv_dy + dv_dx * du_dy) * m->m_xy;
    return r;
}

mf_slope_cross_moments mf_moments_cross_from_normals(mf_vec3 nf, mf_vec3 ng)
{
    if (!mf_vec3_isfinite(nf) || !mf_vec3_isfinite(ng) || !(nf.z > 0.0) || !(ng.z > 0.0)) {
        mf_slope_cross_moments bad = {NAN, NAN, NAN, NAN};
        return bad;
    }
    double fx = -nf.x / nf.z, fy = -nf.y / nf.z, gx = -ng.x / ng.z, gy = -ng.y / ng.z;
    mf_slope_cross_moments c = {fx * gx, fy * gy, fx * gy, fy * gx};
    return c;
}

void mf_moments_cross_accumulate(mf_slope_cross_moments *acc, const mf_slope_cross_moments *c, double w)
{
    acc->xx += w * c->xx;
    acc->yy += w * c->yy;
    acc->xy += w * c->xy;
    acc->yx += w * c->yx;
}

mf_slope_cross_moments mf_moments_cross_uncorrelated(const mf_slope_moments *f, const mf_slope_moments *g)
{
    if (!moments_finite(f) || !moments_finite(g)) {
        mf_slope_cross_moments bad = {NAN, NAN, NAN, NAN};
        return bad;
    }
    /* [Olano 2010, Sec. 3.5, mixing approximation] */
    mf_slope_cross_moments c = {f->mean_x * g->mean_x, f->mean_y * g->mean_y, f->mean_x * g->mean_y,
                                f->mean_y * g->mean_x};
    return c;
}

mf_slope_moments mf_moments_mix(const mf_slope_moments *f, const mf_slope_moments *g,
                                const mf_slope_cross_moments *c, double t, double u)
{
    if (!moments_finite(f) || !moments_finite(g) || !c || !isfinite(c->xx) || !isfinite(c->yy)
        || !isfinite(c->xy) || !isfinite(c->yx) || !isfinite(t) || !isfinite(u))
        return moments_nan();
    /* [Olano 2010, Eq. 7-9] */
    double tt = t * t, uu = u * u, tu = t * u;
    mf_slope_moments r;
    r.mean_x = t * f->mean_x + u * g->mean_x;
    r.mean_y = t * f->mean_y + u * g->mean_y;
    r.m_xx = tt * f->m_xx + uu * g->m_xx + 2.0 * tu * c->xx;      /* Eq. 7 */
    r.m_yy = tt * f->m_yy + uu * g->m_yy + 2.0 * tu * c->yy;      /* Eq. 8 */
    r.m_xy = tt * f->m_xy + uu * g->m_xy + tu * (c->xy + c->yx);  /* Eq. 9 */
    return r;
}

mf_eigen2 mf_sym2_eigen(mf_sym2 s)
{
    mf_eigen2 e;
    double a = s.xx, b = s.xy, c = s.yy;
    if (!sym2_finite(s)) {
        e.l1 = e.l2 = e.v1[0] = e.v1[1] = e.v2[0] = e.v2[1] = NAN;
        return e;
    }
    if (b == 0.0) { /* diagonal (correction C-H6): exact eigenvalues, axis-aligned vectors */
        int x_first = a >= c;
        e.l1 = x_first ? a : c;
        e.l2 = x_first ? c : a;
        e.v1[0] = x_first ? 1.0 : 0.0;
        e.v1[1] = x_first ? 0.0 : 1.0;
    } else {
        double m = 0.5 * a + 0.5 * c, d = 0.5 * a - 0.5 * c; /* halves first: no overflow */
        double r = hypot(d, b);                             /* > 0 since b != 0 */
        e.l1 = m + r;
        /* l2 = m - r cancels when l2 << l1; det / l1 is then as accurate as det itself */
        double l2 = m - r;
        if (e.l1 > 0.0 && fabs(l2) < 0.5 * fabs(m))
            l2 = (a / e.l1) * c - (b / e.l1) * b; /* det / l1, scaled first: no overflow */
        e.l2 = l2;
        /* (A - l1 I) v = 0 is solved by (r + d, b) and by (b, r - d); take the one whose
         * large component is a sum of non-negative terms (>= r): no division by a small number. */
        double vx, vy;
        if (d >= 0.0) {
            vx = r + d;
            vy = b;
        } else {
            vx = b;
            vy = r - d;
        }
        double len = hypot(vx, vy);
        e.v1[0] = vx / len;
        e.v1[1] = vy / len;
        if (e.v1[0] < 0.0) { /* canonical sign: v1.x >= 0 */
            e.v1[0] = -e.v1[0];
            e.v1[1] = -e.v1[1];
        }
    }
    e.v2[0] = -e.v1[1];
    e.v2[1] = e.v1[0];
    return e;
}

mf_aniso_roughness mf_roughness_from_covariance(mf_sym2 cov)
{
    mf_aniso_roughness r;
    mf_eigen2 e = mf_sym2_eigen(cov);
    double l2 = e.l2;
    if (!(e.l1 >= 0.0) || !(l2 >= -16.0 * DBL_EPSILON * e.l1)) {
        r.alpha1 = r.alpha2 = r.dir1[0] = r.dir1[1] = r.dir2[0] = r.dir2[1] = NAN;
        return r;
    }
    if (l2 < 0.0)
        l2 = 0.0;
    r.alpha1 = sqrt(2.0 * e.l1); /* alpha^2 = 2 sigma^2 */
    r.alpha2 = sqrt(2.0 * l2);
    r.dir1[0] = e.v1[0];
    r.dir1[1] = e.v1[1];
    r.dir2[0] = e.v2[0];
    r.dir2[1] = e.v2[1];
    return r;
}

mf_sym2 mf_hery_slope_covariance(const mf_slope_moments *dw, double len_ru, double len_rv)
{
    mf_sym2 bad = {NAN, NAN, NAN};
    if (!moments_finite(dw) || !(len_ru > 0.0) || !(len_rv > 0.0) || !isfinite(len_ru) || !isfinite(len_rv))
        return bad;
    /* [Hery 2014, Eq. 7]: sigma^2(x) = f(x^2) - f(x)^2 (with the rounding policy of Eq. 5 above) */
    mf_gaussian_slopes g = mf_moments_to_gaussian(dw);
    if (!mf_gaussian_valid(&g))
        return bad;
    /* Eq. 6, 8, 10 with the slope per unit arc length w_u / |R_u| (correction C-H1; the printed
     * Eq. 4-5 multiply by |R_u|^(1/2)).  No factor 1/2 here (correction C-H2: see bump_roughness). */
    mf_sym2 s = {g.var_x / (len_ru * len_ru), g.cov_xy / (len_ru * len_rv), g.var_y / (len_rv * len_rv)};
    return s;
}

mf_aniso_roughness mf_hery_bump_roughness(double m_orig_x, double m_orig_y, mf_sym2 slope_cov)
{
    if (!(m_orig_x >= 0.0) || !(m_orig_y >= 0.0) || !isfinite(m_orig_x) || !isfinite(m_orig_y)
        || !sym2_finite(slope_cov)) {
        mf_aniso_roughness bad = {NAN, NAN, {NAN, NAN}, {NAN, NAN}};
        return bad;
    }
    /* corrections C-H2 and C-H5: roughness matrix diag(m_orig^2) + 2 Sigma; alpha_k = sqrt(l_k).
     * Written as the covariance diag(m_orig^2 / 2) + Sigma so that alpha_k = sqrt(2 l_k). */
    mf_sym2 cov = {0.5 * m_orig_x * m_orig_x + slope_cov.xx, slope_cov.xy, 0.5 * m_orig_y * m_orig_y + slope_cov.yy};
    return mf_roughness_from_covariance(cov);
}

double mf_toksvig_variance(double len)
{
    if (!(len > 0.0) || !(len <= 1.0))
        return NAN;
    return (1.0 - len) / len; /* [Toksvig 2005]: len = 1 / (1 + sigma^2) */
}

double mf_toksvig_factor(double len, double exponent)
{
    if (!(len > 0.0) || !(len <= 1.0) || !(exponent > 0.0) || !isfinite(exponent))
        return NAN;
    return len / (len + exponent * (1.0 - len)); /* [Toksvig 2005] */
}

double mf_toksvig_beckmann_alpha(double len, double alpha)
{
    double var = mf_toksvig_variance(len);
    if (isnan(var) || !(alpha >= 0.0) || !isfinite(alpha))
        return NAN;
    return sqrt(alpha * alpha + 2.0 * var); /* 1/s' = 1/s + sigma^2 with 1/s = alpha^2 / 2 */
}
