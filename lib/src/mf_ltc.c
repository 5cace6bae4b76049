/*
 * mf_ltc.c -- linearly transformed cosines (see mf_ltc.h; derivations in docs/math.md).
 */
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_sample.h"

static int mat3_isfinite(mf_mat3 a)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (!isfinite(a.m[i][j]))
                return 0;
    return 1;
}

mf_status mf_ltc_init(mf_ltc *ltc, mf_mat3 m)
{
    if (!ltc || !mat3_isfinite(m))
        return MF_ERR_DOMAIN;
    mf_mat3 inv;
    if (mf_mat3_inverse(m, &inv) != MF_OK || !mat3_isfinite(inv))
        return MF_ERR_DOMAIN;
    double det = mf_mat3_det(m);
    double abs_det_inv = 1.0 / fabs(det);
    if (!isfinite(abs_det_inv))
        return MF_ERR_DOMAIN;
    ltc->m = m;
    ltc->inv = inv;
    ltc->det = det;
    ltc->abs_det_inv = abs_det_inv;
    return MF_OK;
}

double mf_ltc_eval(const mf_ltc *ltc, mf_vec3 w)
{
    double len = mf_vec3_length(w);
    if (!ltc || !mf_vec3_isfinite(w) || !(len > 0.0) || !isfinite(len))
        return NAN;
    mf_vec3 u = mf_mat3_apply(ltc->inv, mf_vec3_scale(w, 1.0 / len));
    double r = mf_vec3_length(u);
    if (!(u.z > 0.0))
        return 0.0;
    /* D_o(u/r) |det M^-1| / r^3 with D_o(wo) = wo.z / pi [Nahmias Eq. 2.21, 2.24; docs/math.md, correction C-T2];
     * written as (u.z / r) (|det M^-1| / r^3) so that neither factor overflows first. */
    return (u.z / r) * (ltc->abs_det_inv / (r * r * r)) * MF_INV_PI;
}

mf_vec3 mf_ltc_sample(const mf_ltc *ltc, const double u[2])
{
    if (!ltc)
        return mf_vec3_make(NAN, NAN, NAN);
    /* w = M wo / |M wo|, wo with density max(0, z)/pi [Nahmias Eq. 2.19, 2.24] */
    mf_vec3 w = mf_mat3_apply(ltc->m, mf_sample_cosine_hemisphere(u));
    return mf_vec3_scale(w, 1.0 / mf_vec3_length(w));
}

double mf_ltc_pdf(const mf_ltc *ltc, mf_vec3 w) { return mf_ltc_eval(ltc, w); }

/* P_o = M^-1 P (vertex by vertex; directions, so no normalisation is needed).  0 if p is not
 * valid or a transformed vertex is not (overflow of an ill-conditioned M^-1). */
static int transform_polygon(const mf_ltc *ltc, const mf_polygon *p, mf_polygon *out)
{
    if (!ltc || !mf_polygon_valid(p))
        return 0;
    *out = *p;
    for (int i = 0; i < p->n; ++i)
        out->v[i] = mf_mat3_apply(ltc->inv, p->v[i]);
    return mf_polygon_valid(out);
}

/* The winding of P_o seen from the shading point is that of P times sign(det M^-1). */
static double orientation_sign(const mf_ltc *ltc) { return ltc->det < 0.0 ? -1.0 : 1.0; }

double mf_ltc_integrate_polygon(const mf_ltc *ltc, const mf_polygon *p, mf_polygon_sided sided)
{
    mf_polygon po;
    if (!transform_polygon(ltc, p, &po) || (sided != MF_POLYGON_ONE_SIDED && sided != MF_POLYGON_TWO_SIDED))
        return NAN;
    /* integral over P of D = integral over P_o of D_o [Nahmias Eq. 2.23]: the normalised cosine
     * integral of P_o clipped to z_o >= 0 AFTER the transform (corrections C-T3, C-T4). */
    double e = orientation_sign(ltc) * mf_polygon_integrate_cosine_signed(&po);
    return sided == MF_POLYGON_TWO_SIDED ? fabs(e) : fmax(0.0, e);
}

mf_mat3 mf_ltc_matrix_isotropic(double a, double b, double c, double d)
{
    /* [Heitz et al. 2016; Nahmias Eq. 2.26] */
    mf_mat3 m = {{{a, 0.0, b}, {0.0, c, 0.0}, {d, 0.0, 1.0}}};
    return m;
}

mf_mat3 mf_ltc_matrix_general(const double m9[9])
{
    mf_mat3 m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            m.m[i][j] = m9[3 * i + j];
    return m;
}

mf_frame mf_ltc_view_frame(mf_vec3 wo)
{
    mf_frame f;
    f.n = mf_vec3_make(0.0, 0.0, 1.0);
    if (!mf_vec3_isfinite(wo)) {
        f.s = f.t = f.n = mf_vec3_make(NAN, NAN, NAN);
        return f;
    }
    double r = hypot(wo.x, wo.y);
    f.s = r > 0.0 ? mf_vec3_make(wo.x / r, wo.y / r, 0.0) : mf_vec3_make(1.0, 0.0, 0.0);
    f.t = mf_vec3_cross(f.n, f.s);
    return f;
}

mf_mat3 mf_ltc_matrix_to_world(mf_frame f, mf_mat3 m_local)
{
    mf_mat3 r = {{{f.s.x, f.t.x, f.n.x}, {f.s.y, f.t.y, f.n.y}, {f.s.z, f.t.z, f.n.z}}};
    return mf_mat3_mul(r, m_local);
}

/* atan(z) - z without cancellation: the Taylor series -z^3/3 + z^5/5 - ... for |z| < 0.1
 * (8 terms: the first omitted one is below 1e-16 of the sum), directly above (where the
 * difference keeps all but ~log10(3/z^2) <= 2.5 digits). */
static double atan_minus_x(double z)
{
    if (fabs(z) >= 0.1)
        return atan(z) - z;
    double z2 = z * z, term = z, sum = 0.0;
    for (int k = 1; k <= 8; ++k) {
        term *= -z2;
        sum += term / (2 * k + 1);
    }
    return sum;
}

double mf_ltc_sphere_integral(double f_len, double f_cos)
{
    const double slack = 1e-12;
    if (!(f_len >= 0.0 && f_len <= 1.0 + slack) || !(fabs(f_cos) <= 1.0 + slack))
        return NAN;
    double s2 = fmin(f_len, 1.0);          /* sin^2 sigma */
    double c = fmax(-1.0, fmin(1.0, f_cos)); /* cos theta of the cap's centre */
    if (s2 == 0.0)
        return 0.0;
    if (c * c >= s2)
        return c > 0.0 ? s2 * c : 0.0; /* wholly above (integral of z/pi over a cap) or below */
    /* The horizon cuts the cap: |cos theta| < sin sigma, so sin theta > 0. */
    double sn = sqrt(1.0 - c * c);
    if (s2 == 1.0)
        return 0.5 * (1.0 + c); /* the hemisphere around the centre: x = 0 below */
    double x = sqrt(1.0 - s2) / sqrt(s2); /* cot sigma */
    double y = -x * c / sn;               /* |y| < 1 */
    double q = sn * sqrt(1.0 - y * y);
    /* Snyder's pi I = (c acos y - x q) s2 + atan(q / x).  With z = q / x = q tan sigma,
     * x q s2 = q sin sigma cos sigma = z cos^2 sigma = z - z s2, so
     *   pi I = c acos(y) s2 + (atan(z) - z) + z s2        (used for z < 1)
     *        = c acos(y) s2 + atan(z) - x q s2            (the printed form, for z >= 1).
     * For a small cap (z < 1, sigma small) the printed form subtracts two O(sigma) terms to get
     * O(sigma^3); the first form adds terms of that size (z s2 > 3 (z - atan z), no
     * cancellation).  For z >= 1, cos^2 sigma <= 1/(1 + z^2), so x q s2 <= min(1/2, 1/z) stays
     * well below atan(z) >= pi/4, while the first form would cancel z s2 against atan(z) - z
     * (both ~1e6 for sigma = pi/2 - 1e-6).  (docs/math.md) */
    double z = q / x;
    double t = (z < 1.0) ? atan_minus_x(z) + z * s2 : atan(z) - x * q * s2;
    return (c * acos(y) * s2 + t) * MF_INV_PI;
}

double mf_ltc_integrate_polygon_sphere(const mf_ltc *ltc, const mf_polygon *p, mf_polygon_sided sided)
{
    mf_polygon po;
    if (!transform_polygon(ltc, p, &po) || (sided != MF_POLYGON_ONE_SIDED && sided != MF_POLYGON_TWO_SIDED))
        return NAN;
    double s = orientation_sign(ltc);
    /* F of P_o points into the polygon when P_o is front-facing; make it so for either facing
     * (two-sided) or return 0 for a back-facing P (one-sided).  The facing of P is the sign of
     * its solid angle, times sign(det M^-1) for P_o. */
    double facing = s * mf_polygon_solid_angle_signed(&po);
    if (isnan(facing))
        return NAN;
    if (facing < 0.0 && sided == MF_POLYGON_ONE_SIDED)
        return 0.0;
    mf_vec3 f = mf_vec3_scale(mf_polygon_form_factor(&po), facing < 0.0 ? -s : s);
    double len = mf_vec3_length(f);
    if (!(len > 0.0))
        return len == 0.0 ? 0.0 : NAN;
    return mf_ltc_sphere_integral(len, f.z / len);
}
