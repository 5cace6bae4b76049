/*
 * test_polygon.c -- solid angle, vector form factor and clamped-cosine integral of polygons
 * (mf_polygon.h) against closed forms, symmetries and Monte Carlo.
 *
 * Monte Carlo: E = integral over P of max(0, z)/pi dw is the probability that a direction with
 * the cosine density max(0, z)/pi (mf_sample_cosine_hemisphere) hits P, so the estimate is the
 * hit fraction of N samples, with the binomial standard error sqrt(E (1 - E) / N) of the
 * reference E.  Hits are decided by an independent path: the ray t w (t > 0) meets the plane of
 * the (planar) polygon, and a crossing-number test in the plane decides "inside" (convex or not).
 * The check is |estimate - E| <= z se + delta with z = 4.5 (two-sided p = 6.8e-6 per check, so
 * fewer than 1e-3 false alarms over the < 150 checks here) and delta = 5 / N (five hits: the
 * normal approximation of the binomial fails for expected counts N E below ~10, where a sliver
 * above the horizon could be hit a few times; P(Poisson(1) >= 6) = 6e-4).
 */
#include "mf_test.h"
#include "test_polygon_mc.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"

#include <float.h>
#include <string.h>

#define MC_N 400000
#define MC_Z 4.5
#define MC_DELTA (5.0 / MC_N)
#define DEG (MF_PI / 180.0)

static mf_vec3 v3(double x, double y, double z) { return mf_vec3_make(x, y, z); }

static mf_polygon poly3(mf_vec3 a, mf_vec3 b, mf_vec3 c)
{
    mf_vec3 v[3] = {a, b, c};
    return mf_polygon_make(3, v);
}

static mf_polygon poly4(mf_vec3 a, mf_vec3 b, mf_vec3 c, mf_vec3 d)
{
    mf_vec3 v[4] = {a, b, c, d};
    return mf_polygon_make(4, v);
}

static mf_polygon transformed(mf_mat3 r, const mf_polygon *p)
{
    mf_polygon q = *p;
    for (int i = 0; i < p->n; ++i)
        q.v[i] = mf_mat3_apply(r, p->v[i]);
    return q;
}

/* Square of half-width h in the plane z = 1, centred on the zenith, front-facing (clockwise
 * seen from the origin = counter-clockwise seen from above). */
static mf_polygon zenith_square(double h) { return poly4(v3(h, -h, 1), v3(h, h, 1), v3(-h, h, 1), v3(-h, -h, 1)); }

/* Closed forms for zenith_square(h): the form factor of a parallel square, four corner
 * rectangles of the classic formula F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + (X <-> Y)]
 * (e.g. Howell's catalogue, C-11), and the solid angle of a rectangle,
 * Omega = 4 asin(a b / sqrt((a^2 + d^2)(b^2 + d^2))). */
static double zenith_square_e(double h)
{
    double k = h / sqrt(1.0 + h * h);
    return 4.0 / MF_PI * k * atan(k);
}
static double zenith_square_omega(double h) { return 4.0 * asin(h * h / (1.0 + h * h)); }

/* Hit fraction of MC_N cosine-distributed directions. */
static double mc_cosine(const mf_polygon *p, mf_pcg32 *rng)
{
    long hits = 0;
    for (long k = 0; k < MC_N; ++k) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
        hits += mf_test_ray_hits(p, mf_sample_cosine_hemisphere(u));
    }
    return (double)hits / MC_N;
}

/* A random planar polygon: n vertices (3..8) around a centre direction c at distance 1, in a
 * plane with normal tilted from c by up to 70 degrees, radii in [0.2, 1] * size, angles sorted
 * (convex-ish; star-shaped, so simple) or alternately pulled in (non-convex). */
static mf_polygon random_polygon(mf_pcg32 *rng, mf_vec3 c, double size, int nonconvex)
{
    double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
    mf_vec3 tilt = mf_sample_uniform_sphere(u);
    mf_vec3 nrm = mf_vec3_normalize(mf_vec3_add(c, mf_vec3_scale(tilt, 0.9)));
    if (mf_vec3_dot(nrm, c) < 0.35)
        nrm = c;
    mf_frame f = mf_frame_from_normal(nrm);
    int n = 3 + (int)(mf_pcg32_next_double(rng) * 6.0);
    double ang[8];
    for (int i = 0; i < n; ++i)
        ang[i] = 2.0 * MF_PI * (i + 0.8 * mf_pcg32_next_double(rng)) / n;
    mf_vec3 v[8];
    for (int i = 0; i < n; ++i) {
        double r = size * (0.2 + 0.8 * mf_pcg32_next_double(rng));
        if (nonconvex && (i % 2))
            r *= 0.3;
        v[i] = mf_vec3_add(c, mf_frame_to_world(f, v3(r * cos(ang[i]), r * sin(ang[i]), 0.0)));
    }
    mf_polygon p = mf_polygon_make(n, v);
    return (mf_pcg32_next_u32(rng) & 1u) ? mf_test_reversed(&p) : p;
}

/* ---- tests ----------------------------------------------------------------------------------- */
static void test_closed_forms(void)
{
    /* Octant: Omega = pi/2, E = 1/4 (a quarter of the hemisphere's integral), F = (1,1,1)/4. */
    mf_polygon oct = poly3(v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1));
    CHECK_REL(mf_polygon_solid_angle(&oct), 0.5 * MF_PI, 4 * DBL_EPSILON);
    CHECK_REL(mf_polygon_solid_angle_signed(&oct), 0.5 * MF_PI, 4 * DBL_EPSILON);
    CHECK_REL(mf_polygon_integrate_cosine(&oct, MF_POLYGON_ONE_SIDED), 0.25, 4 * DBL_EPSILON);
    mf_vec3 f = mf_polygon_form_factor(&oct);
    CHECK_REL(f.x, 0.25, 4 * DBL_EPSILON);
    CHECK_REL(f.y, 0.25, 4 * DBL_EPSILON);
    CHECK_REL(f.z, 0.25, 4 * DBL_EPSILON);
    /* reversed: back-facing */
    mf_polygon rev = mf_test_reversed(&oct);
    CHECK_REL(mf_polygon_solid_angle(&rev), 0.5 * MF_PI, 4 * DBL_EPSILON);
    CHECK_REL(mf_polygon_solid_angle_signed(&rev), -0.5 * MF_PI, 4 * DBL_EPSILON);
    CHECK(mf_polygon_integrate_cosine(&rev, MF_POLYGON_ONE_SIDED) == 0.0);
    CHECK_REL(mf_polygon_integrate_cosine(&rev, MF_POLYGON_TWO_SIDED), 0.25, 4 * DBL_EPSILON);
    CHECK_REL(mf_polygon_integrate_cosine_signed(&rev), -0.25, 4 * DBL_EPSILON);

    /* The upper hemisphere as 4 octant triangles: the integrals add up to 1, solid angles to 2 pi. */
    double sum = 0.0, sum_omega = 0.0;
    for (int k = 0; k < 4; ++k) {
        double a = 0.5 * MF_PI * k;
        mf_vec3 p0 = v3(cos(a), sin(a), 0), p1 = v3(-sin(a), cos(a), 0);
        mf_polygon t = poly3(p0, p1, v3(0, 0, 1));
        sum += mf_polygon_integrate_cosine(&t, MF_POLYGON_ONE_SIDED);
        sum_omega += mf_polygon_solid_angle(&t);
    }
    CHECK_REL(sum, 1.0, 8 * DBL_EPSILON);
    CHECK_REL(sum_omega, 2.0 * MF_PI, 8 * DBL_EPSILON);
    /* ... and as one polygon along the horizon (the limit of a polygon covering the hemisphere) */
    mf_polygon eq = poly4(v3(1, 0, 0), v3(0, 1, 0), v3(-1, 0, 0), v3(0, -1, 0));
    CHECK_REL(mf_polygon_integrate_cosine(&eq, MF_POLYGON_ONE_SIDED), 1.0, 8 * DBL_EPSILON);
    /* a large square just above the shading point covers almost all of it: E -> 1 as h -> inf */
    mf_polygon big = zenith_square(1e8);
    CHECK_REL(mf_polygon_integrate_cosine(&big, MF_POLYGON_ONE_SIDED), zenith_square_e(1e8), 16 * DBL_EPSILON);
    CHECK(mf_polygon_integrate_cosine(&big, MF_POLYGON_ONE_SIDED) <= 1.0);

    /* Squares at the zenith, from large to tiny (solid angle 4e-12 for h = 1e-6): the closed
     * forms to 16 eps (a few roundings per edge, four edges, no cancellation at the zenith). */
    static const double hs[] = {10.0, 1.0, 0.5, 1e-3, 1e-6, 1e-9};
    for (int i = 0; i < 6; ++i) {
        mf_polygon sq = zenith_square(hs[i]);
        CHECK_REL(mf_polygon_integrate_cosine(&sq, MF_POLYGON_ONE_SIDED), zenith_square_e(hs[i]), 16 * DBL_EPSILON);
        CHECK_REL(mf_polygon_solid_angle(&sq), zenith_square_omega(hs[i]), 16 * DBL_EPSILON);
        mf_vec3 fs = mf_polygon_form_factor(&sq);
        CHECK_REL(fs.z, zenith_square_e(hs[i]), 16 * DBL_EPSILON);
        CHECK(fabs(fs.x) <= 16 * DBL_EPSILON * fs.z && fabs(fs.y) <= 16 * DBL_EPSILON * fs.z);
    }
}

/* A tiny square tilted away from the zenith: E = E0 cos(tilt) and Omega = Omega0 by rotation
 * invariance (F(R P) = R F(P), F(P) = (0, 0, E0)).  Rotating the vertices rounds their O(1)
 * coordinates by ~eps, which moves the edges (length 2h) by eps/h relative: for h = 1e-6 that is
 * 1e-10, the conditioning of the input itself; tolerance 100 eps / h. */
static void test_tiny_oblique(void)
{
    static const double hs[] = {1e-2, 1e-4, 1e-6};
    static const double tilts[] = {30.0, 60.0, 85.0};
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            mf_polygon sq = zenith_square(hs[i]);
            mf_mat3 r = mf_mat3_mul(mf_test_rotation(v3(0, 0, 1), 0.7), mf_test_rotation(v3(1, 0, 0), tilts[k] * DEG));
            mf_polygon t = transformed(r, &sq);
            double tol = 100 * DBL_EPSILON / hs[i];
            CHECK_REL(mf_polygon_integrate_cosine(&t, MF_POLYGON_ONE_SIDED),
                      zenith_square_e(hs[i]) * cos(tilts[k] * DEG), tol);
            CHECK_REL(mf_polygon_solid_angle(&t), zenith_square_omega(hs[i]), tol);
            CHECK(mf_polygon_integrate_cosine(&t, MF_POLYGON_ONE_SIDED) > 0.0);
        }
}

/* F(R P) = R F(P) for random rotations; E and Omega are invariant under rotations about z. */
static void test_rotations(mf_pcg32 *rng)
{
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
        mf_vec3 c = mf_sample_uniform_sphere(u);
        mf_polygon p = random_polygon(rng, c, 0.1 + mf_pcg32_next_double(rng), k % 3 == 0);
        u[0] = mf_pcg32_next_double(rng);
        u[1] = mf_pcg32_next_double(rng);
        mf_mat3 r = mf_test_rotation(mf_sample_uniform_sphere(u), 2.0 * MF_PI * mf_pcg32_next_double(rng));
        mf_polygon q = transformed(r, &p);
        mf_vec3 fp = mf_polygon_form_factor(&p), fq = mf_polygon_form_factor(&q);
        mf_vec3 rf = mf_mat3_apply(r, fp);
        double err = mf_vec3_length(mf_vec3_sub(fq, rf));
        worst = fmax(worst, err);
        /* |F| <= 1, rounding of O(1) terms: 64 eps absolute */
        CHECK(err <= 64 * DBL_EPSILON);
        CHECK_ABS(mf_polygon_solid_angle(&q), mf_polygon_solid_angle(&p), 64 * DBL_EPSILON);
        mf_polygon z = transformed(mf_test_rotation(v3(0, 0, 1), 2.0 * MF_PI * mf_pcg32_next_double(rng)), &p);
        CHECK_ABS(mf_polygon_integrate_cosine_signed(&z), mf_polygon_integrate_cosine_signed(&p), 64 * DBL_EPSILON);
        /* above the horizon, the clipped integral is F.z */
        int above = 1;
        for (int i = 0; i < p.n; ++i)
            above = above && p.v[i].z > 0.0;
        if (above)
            CHECK_ABS(mf_polygon_integrate_cosine_signed(&p), fp.z, 64 * DBL_EPSILON);
        /* reversing the order negates the signed quantities */
        mf_polygon rv = mf_test_reversed(&p);
        CHECK_ABS(mf_polygon_integrate_cosine_signed(&rv), -mf_polygon_integrate_cosine_signed(&p), 64 * DBL_EPSILON);
        CHECK_ABS(mf_polygon_solid_angle_signed(&rv), -mf_polygon_solid_angle_signed(&p), 64 * DBL_EPSILON);
        CHECK_ABS(mf_polygon_integrate_cosine(&rv, MF_POLYGON_TWO_SIDED),
                  mf_polygon_integrate_cosine(&p, MF_POLYGON_TWO_SIDED), 64 * DBL_EPSILON);
        CHECK(mf_polygon_integrate_cosine(&rv, MF_POLYGON_ONE_SIDED) == 0.0 ||
              mf_polygon_integrate_cosine(&p, MF_POLYGON_ONE_SIDED) == 0.0);
    }
    printf("rotations: worst |F(RP) - R F(P)| = %.3g\n", worst);
}

/* The integral against Monte Carlo with cosine sampling, for random polygons: above the horizon,
 * crossing it (centre within 20 degrees of it), entirely below it, large and small, convex and
 * not. */
static void test_monte_carlo(mf_pcg32 *rng)
{
    double worst_z = 0.0, worst_abs = 0.0;
    int n_cross = 0, n_below = 0;
    for (int k = 0; k < 40; ++k) {
        double elev; /* elevation of the centre above the horizon, degrees */
        int kind = k % 4;
        if (kind == 0)
            elev = 20.0 + 70.0 * mf_pcg32_next_double(rng);
        else if (kind == 3)
            elev = -10.0 - 70.0 * mf_pcg32_next_double(rng);
        else
            elev = -20.0 + 40.0 * mf_pcg32_next_double(rng);
        double az = 2.0 * MF_PI * mf_pcg32_next_double(rng);
        mf_vec3 c = mf_vec3_spherical((90.0 - elev) * DEG, az);
        double size = (k % 5 == 4) ? 0.05 : 0.3 + 1.5 * mf_pcg32_next_double(rng);
        mf_polygon p = random_polygon(rng, c, size, k % 3 == 1);
        if (kind == 3) { /* translate (planarity is kept) entirely below the horizon */
            double zmax = -INFINITY;
            for (int i = 0; i < p.n; ++i)
                zmax = fmax(zmax, p.v[i].z);
            for (int i = 0; i < p.n; ++i)
                p.v[i].z -= fmax(0.0, zmax) + 0.01;
        }
        int any_above = 0, any_below = 0;
        for (int i = 0; i < p.n; ++i) {
            any_above |= p.v[i].z > 0.0;
            any_below |= p.v[i].z < 0.0;
        }
        n_cross += any_above && any_below;
        n_below += !any_above;
        double e = mf_polygon_integrate_cosine(&p, MF_POLYGON_TWO_SIDED);
        double est = mc_cosine(&p, rng);
        double se = sqrt(fmax(e * (1.0 - e), 0.0) / MC_N);
        CHECK_MC(est, se, e, MC_Z, MC_DELTA);
        if (!any_above)
            CHECK(e == 0.0 && mf_polygon_integrate_cosine(&p, MF_POLYGON_ONE_SIDED) == 0.0);
        if (se > 0.0)
            worst_z = fmax(worst_z, fabs(est - e) / se);
        worst_abs = fmax(worst_abs, fabs(est - e));
    }
    CHECK(n_cross >= 10 && n_below >= 8);
    printf("monte carlo: 40 polygons (%d crossing the horizon, %d below), N = %d: worst |est - E| = %.3g, "
           "worst |est - E| / se = %.2f\n",
           n_cross, n_below, MC_N, worst_abs, worst_z);
}

/* The vector form factor against Monte Carlo with uniform sphere sampling: F = (1/pi) integral
 * over P of w dw = 4 E[w 1_P(w)], per component; se from the sample variance. */
static void test_form_factor_mc(mf_pcg32 *rng)
{
    mf_polygon ps[3] = {poly4(v3(1, 2, -1), v3(1, 2, 1), v3(-1, 2, 1), v3(-1, 2, -1)), /* vertical, crossing */
                        poly3(v3(0.3, 0.2, -1), v3(-0.4, 0.3, -1), v3(0.1, -0.5, -1)),  /* below */
                        poly3(v3(1, 0, 0.2), v3(0, 1, 0.2), v3(0, 0, 1))};
    for (int k = 0; k < 3; ++k) {
        /* make each front-facing so that F points into it */
        if (mf_polygon_solid_angle_signed(&ps[k]) < 0.0)
            ps[k] = mf_test_reversed(&ps[k]);
        mf_vec3 f = mf_polygon_form_factor(&ps[k]);
        double s[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
        for (long n = 0; n < MC_N; ++n) {
            double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
            mf_vec3 w = mf_sample_uniform_sphere(u);
            if (!mf_test_ray_hits(&ps[k], w))
                continue;
            double c[3] = {4 * w.x, 4 * w.y, 4 * w.z};
            for (int i = 0; i < 3; ++i) {
                s[i] += c[i];
                s2[i] += c[i] * c[i];
            }
        }
        double ref[3] = {f.x, f.y, f.z};
        for (int i = 0; i < 3; ++i) {
            double mean = s[i] / MC_N, se = sqrt((s2[i] / MC_N - mean * mean) / (MC_N - 1));
            CHECK_MC(mean, se, ref[i], MC_Z, 4.0 * MC_DELTA); /* |4 w_i| <= 4 per hit */
        }
    }
}

/* Nearly degenerate and degenerate polygons: finite, and the right limits. */
static void test_degenerate(void)
{
    /* collinear vertices: zero area */
    mf_polygon col = poly3(v3(0.1, 0.2, 1), v3(0.2, 0.3, 1), v3(0.3, 0.4, 1));
    CHECK_ABS(mf_polygon_integrate_cosine(&col, MF_POLYGON_TWO_SIDED), 0.0, 1e-17);
    CHECK_ABS(mf_polygon_solid_angle(&col), 0.0, 1e-17);
    /* nearly collinear: tiny, of either sign, finite */
    mf_polygon ncol = poly3(v3(0.1, 0.2, 1), v3(0.2, 0.3 + 1e-13, 1), v3(0.3, 0.4, 1));
    CHECK(isfinite(mf_polygon_integrate_cosine(&ncol, MF_POLYGON_TWO_SIDED)));
    CHECK(mf_polygon_integrate_cosine(&ncol, MF_POLYGON_TWO_SIDED) < 1e-13);
    /* repeated vertices: a triangle written as a quad */
    mf_polygon tri = poly3(v3(0.1, 0.2, 1), v3(0.5, 0.3, 1), v3(0.2, 0.6, 1));
    mf_polygon dup = poly4(v3(0.1, 0.2, 1), v3(0.5, 0.3, 1), v3(0.5, 0.3, 1), v3(0.2, 0.6, 1));
    CHECK_REL(mf_polygon_integrate_cosine_signed(&dup), mf_polygon_integrate_cosine_signed(&tri), 8 * DBL_EPSILON);
    CHECK_REL(mf_polygon_solid_angle(&dup), mf_polygon_solid_angle(&tri), 8 * DBL_EPSILON);
    /* all vertices equal */
    mf_polygon pt = poly3(v3(0.3, 0.2, 1), v3(0.3, 0.2, 1), v3(0.3, 0.2, 1));
    CHECK(mf_polygon_integrate_cosine(&pt, MF_POLYGON_TWO_SIDED) == 0.0 && mf_polygon_solid_angle(&pt) == 0.0);
    /* a polygon in a plane through the shading point (exactly antipodal vertices, the shading
     * point on an edge): zero solid angle; the integral is finite */
    mf_polygon thru = poly4(v3(1, 0, 0.5), v3(-1, 0, -0.5), v3(-1, 1, -0.5), v3(1, 1, 0.5));
    CHECK(isfinite(mf_polygon_integrate_cosine(&thru, MF_POLYGON_TWO_SIDED)));
    CHECK(isfinite(mf_polygon_solid_angle(&thru)));
    /* nearly antipodal neighbours (a long thin polygon almost through the shading point) */
    mf_polygon nanti = poly3(v3(1, 1e-12, 0.3), v3(-1, 1e-12, -0.3), v3(0, 1, 0));
    CHECK(isfinite(mf_polygon_integrate_cosine(&nanti, MF_POLYGON_TWO_SIDED)));
    mf_vec3 fn = mf_polygon_form_factor(&nanti);
    CHECK(mf_vec3_isfinite(fn));
    /* edges through the normal and a vertex on it: as the same polygon rotated about z */
    mf_polygon thz = poly4(v3(0, 0, 1), v3(-0.5, -0.5, 1), v3(0.5, -0.5, 1), v3(0.5, 0.5, 1));
    mf_polygon thz2 = poly3(v3(-1, 0, 1), v3(1, 1e-17, 1), v3(0, 1, 1)); /* edge through (0,0,1) */
    for (int k = 1; k < 8; ++k) {
        mf_mat3 r = mf_test_rotation(v3(0, 0, 1), 0.9 * k);
        mf_polygon a = transformed(r, &thz), b = transformed(r, &thz2);
        CHECK_REL(mf_polygon_integrate_cosine_signed(&a), mf_polygon_integrate_cosine_signed(&thz), 32 * DBL_EPSILON);
        CHECK_REL(mf_polygon_integrate_cosine_signed(&b), mf_polygon_integrate_cosine_signed(&thz2), 32 * DBL_EPSILON);
    }
    /* zenith square split through the normal into two rectangles: the halves add up */
    mf_polygon sq = zenith_square(0.5);
    mf_polygon h1 = poly4(v3(0.5, -0.5, 1), v3(0.5, 0.5, 1), v3(0, 0.5, 1), v3(0, -0.5, 1));
    mf_polygon h2 = poly4(v3(0, -0.5, 1), v3(0, 0.5, 1), v3(-0.5, 0.5, 1), v3(-0.5, -0.5, 1));
    CHECK_REL(mf_polygon_integrate_cosine_signed(&h1) + mf_polygon_integrate_cosine_signed(&h2),
              mf_polygon_integrate_cosine_signed(&sq), 16 * DBL_EPSILON);
    /* a vertex exactly on the horizon: continuous with the vertex just above or just below */
    for (int s = 0; s < 2; ++s) {
        double z0 = 0.0, zs = s ? 1e-300 : -1e-300;
        mf_polygon on = poly4(v3(1, -0.3, z0), v3(0.4, 0.6, 0.5), v3(-0.5, 0.2, 0.4), v3(0.2, -0.8, -0.3));
        mf_polygon off = on;
        off.v[0].z = zs;
        CHECK_ABS(mf_polygon_integrate_cosine_signed(&on), mf_polygon_integrate_cosine_signed(&off), 8 * DBL_EPSILON);
        /* a whole edge on the horizon */
        mf_polygon edge = poly4(v3(1, -0.3, 0), v3(0.4, 0.6, 0.5), v3(-0.5, 0.2, 0.4), v3(0.2, -0.8, 0));
        mf_polygon edge2 = edge;
        edge2.v[0].z = edge2.v[3].z = zs;
        CHECK_ABS(mf_polygon_integrate_cosine_signed(&edge), mf_polygon_integrate_cosine_signed(&edge2),
                  8 * DBL_EPSILON);
    }
    /* scale invariance, including coordinates that would overflow or underflow when squared */
    mf_polygon p = poly4(v3(1, -0.3, 0.2), v3(0.4, 0.6, 0.5), v3(-0.5, 0.2, 0.4), v3(0.2, -0.8, -0.3));
    static const double scales[] = {1e-200, 1e-5, 3.0, 1e200};
    for (int i = 0; i < 4; ++i) {
        mf_polygon q = p;
        for (int k = 0; k < q.n; ++k)
            q.v[k] = mf_vec3_scale(q.v[k], scales[i]);
        CHECK_REL(mf_polygon_integrate_cosine_signed(&q), mf_polygon_integrate_cosine_signed(&p), 8 * DBL_EPSILON);
        CHECK_REL(mf_polygon_solid_angle(&q), mf_polygon_solid_angle(&p), 8 * DBL_EPSILON);
    }
}

static void test_domain(void)
{
    mf_vec3 v[9];
    for (int i = 0; i < 9; ++i)
        v[i] = v3(cos(i), sin(i), 1.0);
    mf_polygon p2 = mf_polygon_make(2, v), p9 = mf_polygon_make(9, v), p8 = mf_polygon_make(8, v);
    CHECK(p2.n == 0 && p9.n == 0 && p8.n == 8);
    CHECK(isnan(mf_polygon_integrate_cosine(&p2, MF_POLYGON_TWO_SIDED)));
    CHECK(isnan(mf_polygon_solid_angle(&p9)));
    CHECK(isfinite(mf_polygon_integrate_cosine(&p8, MF_POLYGON_TWO_SIDED)));
    CHECK(isnan(mf_polygon_integrate_cosine(NULL, MF_POLYGON_TWO_SIDED)));
    CHECK(isnan(mf_polygon_integrate_cosine(&p8, (mf_polygon_sided)7)));
    mf_polygon bad = p8;
    bad.v[3] = v3(NAN, 0, 1);
    CHECK(!mf_polygon_valid(&bad) && isnan(mf_polygon_integrate_cosine(&bad, MF_POLYGON_ONE_SIDED)));
    bad.v[3] = v3(INFINITY, 0, 1);
    CHECK(isnan(mf_polygon_solid_angle(&bad)));
    bad.v[3] = v3(0, 0, 0);
    CHECK(isnan(mf_polygon_form_factor(&bad).x));
    bad.n = 12;
    CHECK(!mf_polygon_valid(&bad));
}

int main(void)
{
    uint64_t seed = mf_test_seed(0x9e3779b97f4a7c15ULL);
    mf_pcg32 rng;
    test_closed_forms();
    test_tiny_oblique();
    mf_pcg32_seed(&rng, seed, 1);
    test_rotations(&rng);
    mf_pcg32_seed(&rng, seed, 2);
    test_monte_carlo(&rng);
    mf_pcg32_seed(&rng, seed, 3);
    test_form_factor_mc(&rng);
    test_degenerate();
    test_domain();
    MF_TEST_MAIN_END();
}
