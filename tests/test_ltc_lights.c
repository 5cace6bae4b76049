/*
 * test_ltc_lights.c -- line and disk lights (mf_ltc_lights.h) against numerical integration.
 *
 * References are Gauss-Legendre quadratures of the defining integrals, split where the integrand
 * has a kink (the support boundary of D, the horizon), so they are accurate to ~1e-13; the
 * tolerances below are stated per check.
 */
#include "mf_test.h"
#include "mfkit/mf_ltc_lights.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_rng.h"

#define NGL 32
#define PANELS 64
static double gl_x[NGL], gl_w[NGL];

static double rnd(mf_pcg32 *r, double lo, double hi) { return lo + (hi - lo) * mf_pcg32_next_double(r); }

/* integral over l in [a, b] of D(p(l)) |p x t| / |p|^3, p(l) = p1 + l t; D the LTC (or the cosine
 * when ltc is NULL) */
static double line_integrand(const mf_ltc *ltc, mf_vec3 p1, mf_vec3 t, double l)
{
    mf_vec3 p = mf_vec3_add(p1, mf_vec3_scale(t, l));
    double r = mf_vec3_length(p);
    double dens = ltc ? mf_ltc_eval(ltc, p) : fmax(0.0, p.z / r) * MF_INV_PI;
    return dens * mf_vec3_length(mf_vec3_cross(p, t)) / (r * r * r);
}

static double line_quad(const mf_ltc *ltc, mf_vec3 p1, mf_vec3 t, double a, double b)
{
    double s = 0.0, h = (b - a) / PANELS;
    for (int k = 0; k < PANELS; ++k)
        for (int i = 0; i < NGL; ++i)
            s += 0.5 * h * gl_w[i] * line_integrand(ltc, p1, t, a + h * (k + 0.5 + 0.5 * gl_x[i]));
    return s;
}

/* numerical L(p1, p2), split at the support boundary (M^-1 p(l)).z = 0 (linear in l) */
static double line_reference(const mf_ltc *ltc, mf_vec3 p1, mf_vec3 p2)
{
    mf_vec3 e = mf_vec3_sub(p2, p1);
    double len = mf_vec3_length(e);
    mf_vec3 t = mf_vec3_scale(e, 1.0 / len);
    double z1 = ltc ? mf_mat3_apply(ltc->inv, p1).z : p1.z, z2 = ltc ? mf_mat3_apply(ltc->inv, p2).z : p2.z;
    if ((z1 < 0.0) != (z2 < 0.0)) {
        double lc = len * z1 / (z1 - z2);
        return line_quad(ltc, p1, t, 0.0, lc) + line_quad(ltc, p1, t, lc, len);
    }
    return line_quad(ltc, p1, t, 0.0, len);
}

/* (1/pi) integral of w dw over the ellipse (c, v1, v2) (vec), and the integral of the LTC's D over
 * it (*d_int, when ltc is given): polar coordinates on the ellipse, dw = |n.X| |v1 x v2| rho / |X|^3 */
static mf_vec3 ellipse_reference(const mf_ltc *ltc, mf_vec3 c, mf_vec3 v1, mf_vec3 v2, double *d_int)
{
    enum { NPHI = 512 };
    mf_vec3 nv = mf_vec3_cross(v1, v2);
    mf_vec3 f = {0, 0, 0};
    double dsum = 0.0;
    for (int j = 0; j < NPHI; ++j) { /* trapezoid in phi: exponential convergence (periodic) */
        double phi = 2.0 * MF_PI * (j + 0.5) / NPHI;
        mf_vec3 dir = mf_vec3_add(mf_vec3_scale(v1, cos(phi)), mf_vec3_scale(v2, sin(phi)));
        for (int k = 0; k < 4; ++k)
            for (int i = 0; i < NGL; ++i) {
                double rho = 0.25 * (k + 0.5 + 0.5 * gl_x[i]);
                mf_vec3 x = mf_vec3_add(c, mf_vec3_scale(dir, rho));
                double r = mf_vec3_length(x);
                double dw = fabs(mf_vec3_dot(nv, x)) * rho / (r * r * r) * (0.125 * gl_w[i]) * (2.0 * MF_PI / NPHI);
                f = mf_vec3_add(f, mf_vec3_scale(x, dw / r));
                if (ltc)
                    dsum += mf_ltc_eval(ltc, x) * dw;
            }
    }
    if (d_int)
        *d_int = dsum;
    return mf_vec3_scale(f, MF_INV_PI);
}

static mf_ltc random_ltc(mf_pcg32 *r)
{
    for (;;) {
        double m9[9];
        for (int i = 0; i < 9; ++i)
            m9[i] = rnd(r, -0.6, 0.6) + ((i % 4) == 0 ? rnd(r, 0.3, 1.5) : 0.0);
        mf_ltc ltc;
        if (mf_ltc_init(&ltc, mf_ltc_matrix_general(m9)) == MF_OK && fabs(ltc.det) > 0.05)
            return ltc;
    }
}

static mf_vec3 rvec(mf_pcg32 *r, double lo, double hi)
{
    return mf_vec3_make(rnd(r, lo, hi), rnd(r, lo, hi), rnd(r, lo, hi));
}

int main(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(15), 0);
    CHECK(mf_quad_gauss_legendre(NGL, gl_x, gl_w) == MF_OK);

    /* --- the cosine line integral, random segments (half of them crossing the horizon) --------
     * closed form vs quadrature: relative 1e-11 (the quadrature's accuracy, ~1e-13, and the
     * closed form's rounding of a few ulp times the conditioning of d for lines near the origin) */
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
        mf_vec3 p1 = rvec(&rng, -2.0, 2.0), p2 = rvec(&rng, -2.0, 2.0);
        p1.z = rnd(&rng, -0.5, 2.0);
        double got = mf_line_integrate_cosine(p1, p2), ref = line_reference(NULL, p1, p2);
        if (ref < 1e-6)
            CHECK_ABS(got, ref, 1e-15);
        else {
            CHECK_REL(got, ref, 1e-11);
            worst = fmax(worst, fabs(got - ref) / ref);
        }
    }
    printf("line cosine: worst relative error %.3g over 200 segments\n", worst);
    /* an infinite line at distance 1 straight above: integral of (1/pi) cos^2 phi / 1 over phi in
     * (-pi/2, pi/2) ... of z/pi * d/|p|^3 dl = (1/pi) int dl / (1 + l^2)^2 = 1/2 */
    CHECK_REL(mf_line_integrate_cosine(mf_vec3_make(-1e7, 0, 1), mf_vec3_make(1e7, 0, 1)), 0.5, 1e-12);
    CHECK(mf_line_integrate_cosine(mf_vec3_make(1, 0, -1), mf_vec3_make(0, 1, -0.5)) == 0.0);
    CHECK(mf_line_integrate_cosine(mf_vec3_make(1, 1, 1), mf_vec3_make(2, 2, 2)) == 0.0); /* end-on */
    CHECK(isnan(mf_line_integrate_cosine(mf_vec3_make(NAN, 0, 1), mf_vec3_make(1, 0, 1))));

    /* --- the LTC line integral: random LTCs, random segments; quadrature of D along the line.
     * Relative 1e-10: as above, with the transform's rounding times its condition number (< 1e2). */
    worst = 0.0;
    int nonzero = 0;
    for (int k = 0; k < 200; ++k) {
        mf_ltc ltc = random_ltc(&rng);
        mf_vec3 p1 = rvec(&rng, -2.0, 2.0), p2 = rvec(&rng, -2.0, 2.0);
        double got = mf_ltc_integrate_line(&ltc, p1, p2), ref = line_reference(&ltc, p1, p2);
        if (ref < 1e-6)
            CHECK_ABS(got, ref, 1e-14);
        else {
            ++nonzero;
            CHECK_REL(got, ref, 1e-10);
            worst = fmax(worst, fabs(got - ref) / ref);
        }
    }
    CHECK(nonzero >= 100);
    printf("ltc line: worst relative error %.3g over %d segments with a non-zero integral\n", worst, nonzero);

    /* --- the line as the limit of a thin quad (mf_ltc_integrate_polygon, two-sided) of width eps
     * perpendicular to the plane through the shading point: relative 1e-5 (the O(eps/distance) =
     * 1e-6 of the finite width, and the quad's cancellation, ~1e-16 / (eps / distance) ~ 1e-10) */
    for (int k = 0; k < 50; ++k) {
        mf_ltc ltc = random_ltc(&rng);
        mf_vec3 p1 = rvec(&rng, -2.0, 2.0), p2 = rvec(&rng, -2.0, 2.0);
        p1.z = fabs(p1.z) + 0.2;
        p2.z = fabs(p2.z) + 0.2;
        double eps = 1e-6;
        mf_vec3 n = mf_vec3_normalize(mf_vec3_cross(p1, p2));
        mf_vec3 o = mf_vec3_scale(n, 0.5 * eps);
        mf_vec3 v[4] = {mf_vec3_add(p1, o), mf_vec3_add(p2, o), mf_vec3_sub(p2, o), mf_vec3_sub(p1, o)};
        mf_polygon quad = mf_polygon_make(4, v);
        double ribbon = mf_ltc_integrate_polygon(&ltc, &quad, MF_POLYGON_TWO_SIDED) / eps;
        double got = mf_ltc_integrate_line(&ltc, p1, p2);
        if (got > 1e-3)
            CHECK_REL(got, ribbon, 1e-5);
        else
            CHECK_ABS(got, ribbon, 1e-8);
    }

    /* --- the ellipse's form factor vs quadrature: random ellipses (non-perpendicular v1, v2 too)
     * in front of the shading point.  Absolute 1e-10 per component (quadrature ~1e-13, the cubic's
     * root after a Newton step ~1e-15 of its scale). */
    worst = 0.0;
    for (int k = 0; k < 100; ++k) {
        mf_vec3 c = rvec(&rng, -1.5, 1.5), v1 = rvec(&rng, -0.6, 0.6), v2 = rvec(&rng, -0.6, 0.6);
        mf_vec3 n = mf_vec3_normalize(mf_vec3_cross(v1, v2));
        double h = mf_vec3_dot(n, c);
        if (fabs(h) < 0.2) /* keep the plane away from the shading point: a smooth integrand */
            c = mf_vec3_add(c, mf_vec3_scale(n, (h < 0 ? -1.0 : 1.0) * 0.3));
        mf_vec3 got = mf_ellipse_form_factor(c, v1, v2), ref = ellipse_reference(NULL, c, v1, v2, NULL);
        double err = mf_vec3_length(mf_vec3_sub(got, ref));
        CHECK_ABS(err, 0.0, 1e-10);
        worst = fmax(worst, err);
    }
    printf("ellipse form factor: worst |F - F_quad| %.3g over 100 ellipses\n", worst);
    /* a disk of radius R at height h on the axis: |F| = sin^2 sigma = R^2 / (R^2 + h^2) */
    mf_vec3 fd = mf_ellipse_form_factor(mf_vec3_make(0, 0, 2), mf_vec3_make(1, 0, 0), mf_vec3_make(0, 1, 0));
    CHECK_REL(fd.z, 0.2, 1e-14);
    CHECK_ABS(hypot(fd.x, fd.y), 0.0, 1e-15);
    CHECK(isnan(mf_ellipse_form_factor(mf_vec3_make(1, 0, 0), mf_vec3_make(1, 0, 0), mf_vec3_make(0, 1, 0)).x));

    /* --- the LTC disk integral vs quadrature of D over the disk, where the equivalent cap lies
     * above the horizon and the transformed ellipse does too (then the sphere formula is exact):
     * relative 1e-9 (the quadrature's ~1e-13 and the conditioning of the LTC, < 1e2) */
    int exact = 0, tried = 0;
    while (exact < 60 && tried < 5000) {
        ++tried;
        mf_ltc ltc = random_ltc(&rng);
        mf_vec3 c = rvec(&rng, -1.5, 1.5), v1 = rvec(&rng, -0.5, 0.5), v2 = rvec(&rng, -0.5, 0.5);
        mf_vec3 fo = mf_ellipse_form_factor(mf_mat3_apply(ltc.inv, c), mf_mat3_apply(ltc.inv, v1),
                                            mf_mat3_apply(ltc.inv, v2));
        double fl = mf_vec3_length(fo);
        if (!(fl > 1e-3) || !(fo.z * fo.z / (fl * fl) >= fl * 1.05) || !(fo.z > 0.0))
            continue; /* the cap reaches the horizon: approximation, checked below */
        /* and the transformed ellipse itself above the horizon, with a margin (D smooth on it) */
        mf_vec3 co = mf_mat3_apply(ltc.inv, c), ao = mf_mat3_apply(ltc.inv, v1), bo = mf_mat3_apply(ltc.inv, v2);
        if (!(co.z - hypot(ao.z, bo.z) > 0.05 * mf_vec3_length(co)))
            continue;
        mf_vec3 n = mf_vec3_normalize(mf_vec3_cross(v1, v2));
        if (fabs(mf_vec3_dot(n, c)) < 0.2)
            continue;
        double d_int;
        (void)ellipse_reference(&ltc, c, v1, v2, &d_int);
        double got = mf_ltc_integrate_disk(&ltc, c, v1, v2, MF_POLYGON_TWO_SIDED);
        CHECK_REL(got, d_int, 1e-9);
        ++exact;
    }
    CHECK(exact == 60);
    /* one-sided: the ellipse (c, v1, v2) faces the shading point iff (v1 x v2).c > 0 */
    {
        mf_ltc id;
        CHECK(mf_ltc_init(&id, mf_ltc_matrix_isotropic(1, 0, 1, 0)) == MF_OK);
        mf_vec3 c = mf_vec3_make(0.2, 0.1, 1.0), v1 = mf_vec3_make(0.3, 0, 0), v2 = mf_vec3_make(0, 0.3, 0);
        double front = mf_ltc_integrate_disk(&id, c, v1, v2, MF_POLYGON_ONE_SIDED);
        CHECK(front > 0.0);
        CHECK(mf_ltc_integrate_disk(&id, c, v2, v1, MF_POLYGON_ONE_SIDED) == 0.0);
        CHECK(mf_ltc_integrate_disk(&id, c, v2, v1, MF_POLYGON_TWO_SIDED) == front);
        /* the same orientation as the inscribed polygon of mf_polygon.h */
        mf_vec3 q[4] = {mf_vec3_add(c, v1), mf_vec3_add(c, v2), mf_vec3_sub(c, v1), mf_vec3_sub(c, v2)};
        mf_polygon pq = mf_polygon_make(4, q);
        CHECK(mf_ltc_integrate_polygon(&id, &pq, MF_POLYGON_ONE_SIDED) > 0.0);
    }
    /* a horizon-cut disk facing the shading point is a spherical cap, for which the sphere formula is
     * exact even when cut [Snyder 1996]; the quadrature is not split at the horizon (a kink), so
     * relative 1e-5.  Then an elongated ellipse at the same place: the approximation's error,
     * printed and bounded by 0.1 of the exact value. */
    {
        mf_ltc id;
        CHECK(mf_ltc_init(&id, mf_ltc_matrix_isotropic(1, 0, 1, 0)) == MF_OK);
        double th = 80.0 * MF_PI / 180.0;
        mf_vec3 c = mf_vec3_make(sin(th), 0, cos(th));
        mf_vec3 v1 = mf_vec3_make(0, 0.5, 0), v2 = mf_vec3_make(-0.5 * cos(th), 0, 0.5 * sin(th));
        double d_int;
        (void)ellipse_reference(&id, c, v1, v2, &d_int);
        double got = mf_ltc_integrate_disk(&id, c, v1, v2, MF_POLYGON_TWO_SIDED);
        printf("horizon-cut disk: sphere formula %.9f, quadrature %.9f\n", got, d_int);
        CHECK_REL(got, d_int, 1e-5);
        v1 = mf_vec3_make(0, 0.8, 0);
        v2 = mf_vec3_scale(v2, 0.4);
        (void)ellipse_reference(&id, c, v1, v2, &d_int);
        got = mf_ltc_integrate_disk(&id, c, v1, v2, MF_POLYGON_TWO_SIDED);
        printf("horizon-cut ellipse: sphere approximation %.6f, quadrature %.6f\n", got, d_int);
        CHECK_REL(got, d_int, 0.1);
    }
    MF_TEST_MAIN_END();
}
